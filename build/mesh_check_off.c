/* The OFF checker (mesh_check.h).
 *
 * Compiled for the x86-64 baseline. */

#include "build/mesh_check.h"

/* Next line that is neither blank nor a comment; *cur at its start. */
static int off_line(mesh_stream *s, const char **cur)
{
    int r;
    while ((r = mesh_get_line(s)) > 0) {
        const char *p = s->ln;
        while (*p && is_space(*p))
            p++;
        if (*p && *p != '#') {
            char *hash = strchr(s->ln, '#');
            if (hash)
                *hash = '\0';
            *cur = p;
            return 1;
        }
    }
    return r;
}

/* A line of the vertex or face list. Assimp 5.2 skips only empty lines
 * there: a comment or a line of blanks is read as a vertex (an error) or a
 * face (dropped, and counted, so the last real face is lost; a run of
 * such lines made it crash, found by fuzz_mesh_off). The OFF format allows
 * comments anywhere, but a file that has them in its lists is not read
 * correctly, so it is refused with the line. */
static int off_body_line(mesh_stream *s, const char **cur, const char *what)
{
    int r;
    while ((r = mesh_get_line(s)) > 0) {
        if (s->ln_len == 0)
            continue;
        const char *p = s->ln;
        while (*p && is_space(*p))
            p++;
        if (!*p || *p == '#') {
            mesh_fail_line(s, "%s inside the %s list (Assimp cannot read OFF files with these; "
                              "remove the line)",
                           *p ? "comment" : "line of blanks", what);
            return -1;
        }
        char *hash = strchr(s->ln, '#');
        if (hash)
            *hash = '\0';
        *cur = p;
        return 1;
    }
    return r;
}

bool mesh_is_off_keyword(mesh_tok t)
{
    /* [ST][C][N]OFF; 4OFF and nOFF are other dimensions, not meshes. */
    if (t.n < 3 || t.n > 6 || memcmp(t.p + t.n - 3, "OFF", 3) != 0)
        return false;
    for (size_t i = 0; i + 3 < t.n; i++)
        if (!strchr("STCN", t.p[i]))
            return false;
    return true;
}

bool mesh_check_off(mesh_stream *s)
{
    const char *cur;
    mesh_tok t;
    int r = off_line(s, &cur);
    if (r < 0)
        return false;
    if (r == 0 || !next_tok(&cur, &t) || !mesh_is_off_keyword(t)) {
        char b[48];
        return mesh_fail_line(s, "not an OFF file: expected 'OFF', found '%s'",
                              r == 0 ? "end of file" : mesh_tok_str(t, b));
    }
    long long counts[2];
    int have = 0;
    while (have < 2) {
        if (!next_tok(&cur, &t)) {
            r = off_line(s, &cur);
            if (r < 0)
                return false;
            if (r == 0)
                return mesh_fail_line(s, "file ends before the vertex and face counts");
            continue;
        }
        char b[48];
        if (have == 0 && tok_is(t, "BINARY"))
            return mesh_fail_line(s, "binary OFF is not supported");
        if (mesh_parse_uint(t, &counts[have]) != NUM_OK)
            return mesh_fail_line(s, "bad count '%s' in the OFF header", mesh_tok_str(t, b));
        have++;
    }
    unsigned long long nv = (unsigned long long)counts[0], nf = (unsigned long long)counts[1];
    if (nv == 0 || nv > MAX_VERTICES)
        return mesh_fail_line(s, "vertex count %llu out of range [1, %llu]", nv, MAX_VERTICES);
    if (nf == 0)
        return mesh_fail_line(s, "no faces (a point cloud is not a mesh)");
    if (nf > LANES_SCENE_MAX_TRIANGLES)
        return mesh_fail_line(s, "face count %llu exceeds the limit of %llu", nf,
                              (unsigned long long)LANES_SCENE_MAX_TRIANGLES);
    s->vertices = nv;
    s->faces = nf;
    for (unsigned long long v = 0; v < nv; v++) {
        r = off_body_line(s, &cur, "vertex");
        if (r < 0)
            return false;
        if (r == 0)
            return mesh_fail_line(s, "file ends after %llu of %llu vertices (truncated?)", v, nv);
        if (!mesh_read_xyz(s, &cur, "vertex"))
            return false;
    }
    for (unsigned long long f = 0; f < nf; f++) {
        r = off_body_line(s, &cur, "face");
        if (r < 0)
            return false;
        if (r == 0)
            return mesh_fail_line(s, "file ends after %llu of %llu faces (truncated?)", f, nf);
        long long n, i;
        char b[48];
        if (!next_tok(&cur, &t) || mesh_parse_uint(t, &n) != NUM_OK)
            return mesh_fail_line(s, "bad face: expected a vertex count, found '%s'", mesh_tok_str(t, b));
        /* Assimp 5.2 drops OFF faces of more than 9 vertices without a
         * word; refused rather than lost. */
        if (n < 1 || n > MAX_OFF_POLYGON)
            return mesh_fail_line(s, "face with %lld vertices (OFF faces here have 1 to %d)", n,
                                  MAX_OFF_POLYGON);
        for (long long k = 0; k < n; k++) {
            if (!next_tok(&cur, &t))
                return mesh_fail_line(s, "face lists %llu of its %llu vertex indices",
                                      (unsigned long long)k, (unsigned long long)n);
            if (mesh_parse_uint(t, &i) != NUM_OK)
                return mesh_fail_line(s, "bad vertex index '%s'", mesh_tok_str(t, b));
            if ((unsigned long long)i >= nv)
                return mesh_fail_line(s, "vertex index %s out of range (the file has %llu vertices)",
                                      mesh_tok_str(t, b), nv);
        }
    }
    return true;
}
