/* The STL checker, ASCII and binary (mesh_check.h).
 *
 * Compiled for the x86-64 baseline. */

#include "build/mesh_check.h"

#include <ctype.h>
#include <math.h>
#include <stdint.h>

static bool check_stl_binary(mesh_stream *s, unsigned long count)
{
    unsigned char rec[50];
    for (unsigned long i = 0; i < count; i++) {
        unsigned long long at = mesh_offset(s);
        if (!mesh_get_bytes(s, rec, sizeof rec))
            return mesh_fail_byte(s, at, "file ends in triangle %lu of %lu (truncated?)", i, count);
        for (int k = 3; k < 12; k++) {
            uint32_t w = (uint32_t)rec[4 * k] | (uint32_t)rec[4 * k + 1] << 8 |
                         (uint32_t)rec[4 * k + 2] << 16 | (uint32_t)rec[4 * k + 3] << 24;
            float f;
            memcpy(&f, &w, 4);
            if (!isfinite(f))
                return mesh_fail_byte(s, at + 4 * (unsigned)k,
                                      "triangle %lu: vertex coordinate is not finite", i);
        }
    }
    return true;
}

/* Assimp reads ASCII STL as a stream of tokens, not of lines: a token
 * left over on a line becomes the next statement for it (a "facet normal
 * 0 0 1 endloop" made it build a facet without vertices, then throw, and
 * leak the mesh; found by fuzz_mesh_stl). So statements must end where
 * their line does. */
static bool stl_line_ends(mesh_stream *s, const char *cur, const char *what)
{
    mesh_tok t;
    char b[48];
    if (next_tok(&cur, &t))
        return mesh_fail_line(s, "unexpected '%s' after '%s'", mesh_tok_str(t, b), what);
    return true;
}

static bool check_stl_ascii(mesh_stream *s)
{
    bool in_facet = false, in_loop = false, had_loop = false;
    int nvert = 0;
    unsigned long long facets = 0;
    int r;
    while ((r = mesh_get_line(s)) > 0) {
        const char *cur = s->ln;
        mesh_tok kw;
        char b[48];
        if (!next_tok(&cur, &kw))
            continue;
        if (tok_is_nocase(kw, "solid") || tok_is_nocase(kw, "endsolid")) {
            if (in_facet)
                return mesh_fail_line(s, "'%s' inside a facet", mesh_tok_str(kw, b));
        } else if (tok_is_nocase(kw, "facet")) {
            if (in_facet)
                return mesh_fail_line(s, "'facet' before the previous one ended");
            /* Assimp rejects a malformed normal (and leaks the mesh it was
             * building), so it is checked here first. */
            mesh_tok t;
            if (!next_tok(&cur, &t) || !tok_is_nocase(t, "normal"))
                return mesh_fail_line(s, "expected 'facet normal nx ny nz'");
            for (int k = 0; k < 3; k++) {
                double v;
                if (!next_tok(&cur, &t) || mesh_parse_real_stream(t, &v) == NUM_BAD)
                    return mesh_fail_line(s, "expected 'facet normal nx ny nz'");
            }
            if (!stl_line_ends(s, cur, "facet normal nx ny nz"))
                return false;
            in_facet = true;
            had_loop = false;
            nvert = 0;
        } else if (tok_is_nocase(kw, "outer")) {
            mesh_tok t;
            if (!next_tok(&cur, &t) || !tok_is_nocase(t, "loop"))
                return mesh_fail_line(s, "expected 'outer loop'");
            if (!stl_line_ends(s, cur, "outer loop"))
                return false;
            if (!in_facet || in_loop || had_loop)
                return mesh_fail_line(s, "'outer loop' outside a facet, or a second one in it");
            in_loop = true;
        } else if (tok_is_nocase(kw, "vertex")) {
            if (!in_loop)
                return mesh_fail_line(s, "'vertex' outside a loop");
            if (!mesh_read_xyz(s, &cur, "vertex") || !stl_line_ends(s, cur, "vertex x y z"))
                return false;
            nvert++;
        } else if (tok_is_nocase(kw, "endloop")) {
            if (!stl_line_ends(s, cur, "endloop"))
                return false;
            if (!in_loop)
                return mesh_fail_line(s, "'endloop' without 'outer loop'");
            if (nvert != 3)
                return mesh_fail_line(s, "facet with %llu vertices (STL facets are triangles)",
                                      (unsigned long long)nvert);
            in_loop = false;
            had_loop = true;
        } else if (tok_is_nocase(kw, "endfacet")) {
            if (!stl_line_ends(s, cur, "endfacet"))
                return false;
            if (!in_facet || !had_loop)
                return mesh_fail_line(s, "'endfacet' without a complete facet");
            in_facet = false;
            facets++;
        } else {
            return mesh_fail_line(s, "unexpected '%s' in an ASCII STL file", mesh_tok_str(kw, b));
        }
    }
    if (r < 0)
        return false;
    if (in_facet)
        return mesh_fail_line(s, "file ends inside a facet (truncated?)");
    s->vertices = 3 * facets;
    s->faces = facets;
    if (facets == 0) {
        lanes_error_set(s->err, LANES_ERR_BAD_INPUT, "%s: no facets", s->path);
        return false;
    }
    return true;
}

bool mesh_check_stl(mesh_stream *s, long long size)
{
    unsigned char head[84];
    size_t got = 0;
    while (got < sizeof head && mesh_fill(s)) {
        size_t k = s->len - s->pos < sizeof head - got ? s->len - s->pos : sizeof head - got;
        memcpy(head + got, s->buf + s->pos, k);
        got += k;
        s->pos += k;
    }
    /* The same rule Assimp uses: a file whose size matches its triangle
     * count is binary even when its 80-byte header starts with "solid". */
    if (got == sizeof head) {
        unsigned long count = mesh_stl_declared_count(head);
        /* Assimp's format detection compares in 32 bits, where a huge
         * count wraps around to the file size and the file is taken for
         * binary; refuse such a count here rather than rely on the
         * importer's later size check. */
        if ((uint32_t)(84u + 50u * (uint32_t)count) == (uint32_t)size &&
            (unsigned long long)size != 84ull + 50ull * count) {
            lanes_error_set(s->err, LANES_ERR_BAD_INPUT,
                            "%s: binary STL declares %lu triangles, far more than its "
                            "%lld bytes hold",
                            s->path, count, size);
            return false;
        }
        if ((unsigned long long)size == 84ull + 50ull * count) {
            if (count == 0) {
                lanes_error_set(s->err, LANES_ERR_BAD_INPUT, "%s: binary STL with no triangles", s->path);
                return false;
            }
            s->vertices = 3ull * count;
            s->faces = count;
            return check_stl_binary(s, count);
        }
    }
    if (mesh_starts_solid(head, got)) {
        rewind(s->f);
        s->pos = s->len = 0;
        s->base = 0;
        s->eof = false;
        return check_stl_ascii(s);
    }
    if (got < sizeof head) {
        lanes_error_set(s->err, LANES_ERR_BAD_INPUT,
                        "%s: %lld bytes: too short for a binary STL, and not ASCII "
                        "(no 'solid')",
                        s->path, size);
        return false;
    }
    unsigned long count = mesh_stl_declared_count(head);
    lanes_error_set(s->err, LANES_ERR_BAD_INPUT,
                    "%s: binary STL declares %lu triangles (%llu bytes) but the file "
                    "has %lld bytes (truncated?)",
                    s->path, count, 84ull + 50ull * count, size);
    return false;
}
