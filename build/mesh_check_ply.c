/* The PLY checker, ASCII and binary (mesh_check.h).
 *
 * Compiled for the x86-64 baseline. */

#include "build/mesh_check.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>

typedef enum { PLY_ASCII, PLY_LE, PLY_BE } ply_format;

typedef struct ply_prop {
    int type;       /* index into ply_types */
    int count_type; /* list length type, or -1 for a scalar */
    int role;       /* 0 other, 1..3 x y z, 4 vertex indices */
} ply_prop;

typedef struct ply_elem {
    char name[32];
    unsigned long long count;
    int nprops;
    ply_prop props[64];
} ply_elem;

static const struct {
    const char *name, *alias;
    int size;
    bool is_signed, is_float;
} ply_types[] = {
    {"char", "int8", 1, true, false},    {"uchar", "uint8", 1, false, false},
    {"short", "int16", 2, true, false},  {"ushort", "uint16", 2, false, false},
    {"int", "int32", 4, true, false},    {"uint", "uint32", 4, false, false},
    {"float", "float32", 4, true, true}, {"double", "float64", 8, true, true},
};

static int ply_type(mesh_tok t)
{
    for (int i = 0; i < (int)(sizeof ply_types / sizeof ply_types[0]); i++)
        if (tok_is(t, ply_types[i].name) || tok_is(t, ply_types[i].alias))
            return i;
    return -1;
}

/* One binary value as a double (exact for every integer type here). */
static bool ply_read_bin(mesh_stream *s, ply_format fmt, int type, double *out)
{
    unsigned char b[8];
    int n = ply_types[type].size;
    if (!mesh_get_bytes(s, b, (size_t)n))
        return false;
    unsigned long long u = 0;
    for (int i = 0; i < n; i++) {
        int k = fmt == PLY_LE ? n - 1 - i : i;
        u = (u << 8) | b[k];
    }
    if (ply_types[type].is_float) {
        if (n == 4) {
            uint32_t w = (uint32_t)u;
            float f;
            memcpy(&f, &w, 4);
            *out = f;
        } else {
            double d;
            memcpy(&d, &u, 8);
            *out = d;
        }
    } else if (ply_types[type].is_signed) {
        unsigned long long sign = 1ull << (8 * n - 1);
        *out = (double)(long long)((u ^ sign) - sign);
    } else {
        *out = (double)u;
    }
    return true;
}

typedef struct ply_cursor {
    const char *cur; /* rest of the current ASCII line */
} ply_cursor;

/* ASCII PLY as Assimp 5.2 reads it: one element per line. The format
 * itself is a stream of tokens, but Assimp parses each element from its
 * own line, so a file whose values wrap differently is read as other
 * values ("0 00" on one line and its z on the next made it throw and leak
 * the mesh, found by fuzz_mesh_ply). Blank lines between elements it
 * skips. 1: a line in c; 0: end of file; -1: error. */
static int ply_start_line(mesh_stream *s, ply_cursor *c)
{
    int r;
    while ((r = mesh_get_line(s)) > 0) {
        c->cur = s->ln;
        mesh_tok t;
        const char *peek = s->ln;
        if (next_tok(&peek, &t))
            return 1;
    }
    return r;
}

/* Whether token t names the element stored as `stored` (cut to size - 1
 * characters; two long names that agree that far count as the same). */
static bool ply_same_name(mesh_tok t, const char *stored, size_t size)
{
    if (t.n < size) return tok_is(t, stored);
    return strlen(stored) == size - 1 && memcmp(t.p, stored, size - 1) == 0;
}

/* The header after the 'ply' line, to 'end_header': the format and the
 * elements with their properties (their roles marked). On failure (message
 * set) *elems is freed. */
static bool ply_read_header(mesh_stream *s, ply_format *fmt_out, ply_elem **elems_out, int *nelems_out)
{
    ply_format fmt = PLY_ASCII;
    bool have_format = false;
    ply_elem *elems = NULL;
    int nelems = 0;
    int r;
    for (;;) {
        r = mesh_get_line(s);
        if (r < 0)
            goto done;
        if (r == 0) {
            mesh_fail_line(s, "the header has no 'end_header' (truncated?)");
            goto done;
        }
        const char *cur = s->ln;
        mesh_tok kw, t, u, v;
        char b[48];
        bool blank = !next_tok(&cur, &kw);
        /* Assimp 5.2 reads the format from the line after "ply" and from
         * no other: a comment before it is an error to Assimp, and a
         * second format line, which this check used to follow, made the
         * two read different encodings (found by fuzz_mesh_ply). */
        if (!have_format && (blank || !tok_is(kw, "format"))) {
            mesh_fail_line(s, "the line after 'ply' must be 'format ascii|binary_little_endian|"
                              "binary_big_endian 1.0'");
            goto done;
        }
        if (blank)
            continue;
        if (tok_is(kw, "end_header"))
            break;
        if (tok_is(kw, "comment") || tok_is(kw, "obj_info"))
            continue;
        if (tok_is(kw, "format")) {
            if (have_format) {
                mesh_fail_line(s, "a second 'format' line");
                goto done;
            }
            if (!next_tok(&cur, &t) || !next_tok(&cur, &u) || !tok_is(u, "1.0") ||
                next_tok(&cur, &v)) {
                mesh_fail_line(s, "expected 'format ascii|binary_little_endian|binary_big_endian "
                                  "1.0'");
                goto done;
            }
            if (tok_is(t, "ascii"))
                fmt = PLY_ASCII;
            else if (tok_is(t, "binary_little_endian"))
                fmt = PLY_LE;
            else if (tok_is(t, "binary_big_endian"))
                fmt = PLY_BE;
            else {
                mesh_fail_line(s, "unknown PLY format '%s'", mesh_tok_str(t, b));
                goto done;
            }
            have_format = true;
        } else if (tok_is(kw, "element")) {
            long long n;
            if (!next_tok(&cur, &t) || !next_tok(&cur, &u) || mesh_parse_uint(u, &n) != NUM_OK) {
                mesh_fail_line(s, "'element' needs a name and a count");
                goto done;
            }
            if (nelems == 32) {
                mesh_fail_line(s, "more than 32 elements");
                goto done;
            }
            /* A name declared twice is no PLY file's intent, and Assimp 5.2
             * leaks on it (a second 'face' element: found by
             * fuzz_mesh_ply_binary). */
            for (int i = 0; i < nelems; i++)
                if (ply_same_name(t, elems[i].name, sizeof elems[i].name)) {
                    mesh_fail_line(s, "element '%s' declared twice", elems[i].name);
                    goto done;
                }
            /* Assimp 5.2 keeps only the first triangle of a file's strips
             * and leaks the index arrays of the others (found by
             * fuzz_mesh_ply): silently wrong geometry, so refused. */
            if (tok_is(t, "tristrips") && n > 0) {
                mesh_fail_line(s, "element 'tristrips' is not supported (Assimp 5.2 drops all but "
                                  "the first triangle of the strips); store faces instead");
                goto done;
            }
            ply_elem *e = realloc(elems, (size_t)(nelems + 1) * sizeof *e);
            if (!e) {
                lanes_error_set(s->err, LANES_ERR_OUT_OF_MEMORY, "%s: out of memory", s->path);
                goto done;
            }
            elems = e;
            e = &elems[nelems++];
            memset(e, 0, sizeof *e);
            size_t nn = t.n < sizeof e->name - 1 ? t.n : sizeof e->name - 1;
            memcpy(e->name, t.p, nn);
            e->count = (unsigned long long)n;
        } else if (tok_is(kw, "property")) {
            if (nelems == 0) {
                mesh_fail_line(s, "'property' before any 'element'");
                goto done;
            }
            ply_elem *e = &elems[nelems - 1];
            if (e->nprops == 64) {
                mesh_fail_line(s, "more than 64 properties in element '%s'", e->name);
                goto done;
            }
            ply_prop *p = &e->props[e->nprops];
            if (!next_tok(&cur, &t)) {
                mesh_fail_line(s, "'property' without a type");
                goto done;
            }
            mesh_tok name;
            if (tok_is(t, "list")) {
                if (!next_tok(&cur, &u) || !next_tok(&cur, &v) || !next_tok(&cur, &name) ||
                    (p->count_type = ply_type(u)) < 0 || (p->type = ply_type(v)) < 0 ||
                    ply_types[p->count_type].is_float) {
                    mesh_fail_line(s, "bad list property");
                    goto done;
                }
            } else {
                p->count_type = -1;
                if ((p->type = ply_type(t)) < 0 || !next_tok(&cur, &name)) {
                    mesh_fail_line(s, "bad property type '%s'", mesh_tok_str(t, b));
                    goto done;
                }
            }
            p->role = 0;
            if (strcmp(e->name, "vertex") == 0 && p->count_type < 0) {
                if (tok_is(name, "x"))
                    p->role = 1;
                else if (tok_is(name, "y"))
                    p->role = 2;
                else if (tok_is(name, "z"))
                    p->role = 3;
            }
            if (strcmp(e->name, "face") == 0 && p->count_type >= 0 &&
                (tok_is(name, "vertex_indices") || tok_is(name, "vertex_index")))
                p->role = 4;
            e->nprops++;
        } else {
            mesh_fail_line(s, "unknown header keyword '%s'", mesh_tok_str(kw, b));
            goto done;
        }
    }
    if (!have_format) {
        mesh_fail_line(s, "the header has no 'format' line");
        goto done;
    }
    *fmt_out = fmt;
    *elems_out = elems;
    *nelems_out = nelems;
    return true;
done:
    free(elems);
    return false;
}

/* The vertex count the header declares, after checking the vertex element
 * has x, y and z and some element holds faces; 0 (message set) when not. */
static unsigned long long ply_vertex_count(mesh_stream *s, const ply_elem *elems, int nelems)
{
    unsigned long long nv = 0;
    bool have_vertex = false, have_faces = false;
    for (int i = 0; i < nelems; i++) {
        const ply_elem *e = &elems[i];
        if (strcmp(e->name, "vertex") == 0) {
            int roles = 0;
            for (int k = 0; k < e->nprops; k++)
                roles |= e->props[k].role ? 1 << e->props[k].role : 0;
            if ((roles & 14) != 14) {
                mesh_fail_line(s, "the vertex element lacks x, y or z");
                return 0;
            }
            nv = e->count;
            have_vertex = true;
        }
        if (strcmp(e->name, "face") == 0)
            have_faces = have_faces || e->count > 0;
    }
    if (!have_vertex || nv == 0 || nv > MAX_VERTICES) {
        mesh_fail_line(s, "the header declares %llu vertices (need 1 to %llu)", nv, MAX_VERTICES);
        return 0;
    }
    if (!have_faces) {
        mesh_fail_line(s, "the header declares no faces (a point cloud is not a mesh)");
        return 0;
    }
    return nv;
}

/* The elements' data, as the header declared them: every vertex
 * coordinate a finite float, every face index below nv, no element cut
 * short or (ASCII) running on. */
static bool ply_check_body(mesh_stream *s, ply_format fmt, const ply_elem *elems, int nelems,
                           unsigned long long nv)
{
    int r = 1;
    ply_cursor c = {""};
    for (int i = 0; i < nelems; i++) {
        const ply_elem *e = &elems[i];
        for (unsigned long long j = 0; j < e->count; j++) {
            if (fmt == PLY_ASCII) {
                r = ply_start_line(s, &c);
                if (r < 0)
                    goto done;
                if (r == 0)
                    goto truncated;
            }
            for (int k = 0; k < e->nprops; k++) {
                const ply_prop *p = &e->props[k];
                unsigned long long at = mesh_offset(s);
                double v;
                long long n = 1;
                mesh_tok t;
                char b[48];
                if (p->count_type >= 0) {
                    if (fmt == PLY_ASCII) {
                        if (!next_tok(&c.cur, &t))
                            goto short_line;
                        if ((ply_types[p->count_type].is_signed ? mesh_parse_int(t, &n)
                                                                : mesh_parse_uint(t, &n)) != NUM_OK) {
                            mesh_fail_line(s, "bad list length '%s'", mesh_tok_str(t, b));
                            goto done;
                        }
                    } else {
                        /* v is only set when the read succeeds (at the end of
                         * the file it was converted uninitialized: found by
                         * UBSan under fuzz_mesh_ply_binary). */
                        r = ply_read_bin(s, fmt, p->count_type, &v);
                        if (r > 0)
                            n = (long long)v;
                    }
                    if (r == 0)
                        goto truncated;
                    if (n < 0 || n > MAX_POLYGON) {
                        if (fmt == PLY_ASCII)
                            mesh_fail_line(s, "list of length %s out of range", mesh_tok_str(t, b));
                        else
                            mesh_fail_byte(s, at, "list of length %lld out of range", n);
                        goto done;
                    }
                }
                for (long long m = 0; m < n; m++) {
                    at = mesh_offset(s);
                    int num;
                    if (fmt == PLY_ASCII) {
                        if (!next_tok(&c.cur, &t))
                            goto short_line;
                        num = ply_types[p->type].is_float ? mesh_parse_real_stream(t, &v) : NUM_OK;
                        if (!ply_types[p->type].is_float) {
                            long long iv = 0;
                            num = ply_types[p->type].is_signed ? mesh_parse_int(t, &iv)
                                                               : mesh_parse_uint(t, &iv);
                            v = (double)iv;
                        }
                        if (num == NUM_BAD) {
                            mesh_fail_line(s, "bad number '%s' in element '%s'", mesh_tok_str(t, b), e->name);
                            goto done;
                        }
                    } else {
                        if (!ply_read_bin(s, fmt, p->type, &v))
                            goto truncated;
                        num = isfinite(v) && fabs(v) <= FLT_MAX ? NUM_OK : NUM_NONFINITE;
                    }
                    if (p->role >= 1 && p->role <= 3 && num != NUM_OK) {
                        if (fmt == PLY_ASCII)
                            mesh_fail_line(s, "vertex coordinate '%s' is not a finite float",
                                           mesh_tok_str(t, b));
                        else
                            mesh_fail_byte(s, at, "vertex %llu: coordinate is not a finite float", j);
                        goto done;
                    }
                    if (p->role == 4 && !(v >= 0 && v < (double)nv)) {
                        if (fmt == PLY_ASCII)
                            mesh_fail_line(s,
                                           "vertex index %s out of range (the file has %llu vertices)",
                                           mesh_tok_str(t, b), nv);
                        else
                            mesh_fail_byte(
                                s, at,
                                "face %llu: vertex index out of range (the file has %llu vertices)",
                                j, nv);
                        goto done;
                    }
                }
            }
            if (fmt == PLY_ASCII) {
                mesh_tok t;
                char b[48];
                if (next_tok(&c.cur, &t)) {
                    mesh_fail_line(s, "'%s' after the last property of element '%s' %llu (one "
                                      "element per line)",
                                   mesh_tok_str(t, b), e->name, j);
                    goto done;
                }
            }
            continue;
        short_line:
            mesh_fail_line(s, "element '%s' %llu has fewer values than properties (one element per "
                              "line)",
                           e->name, j);
            goto done;
        truncated:
            if (fmt == PLY_ASCII)
                mesh_fail_line(s, "file ends in element '%s' %llu of %llu (truncated?)", e->name, j,
                               e->count);
            else
                mesh_fail_byte(s, mesh_offset(s),
                               "file ends in element '%s' %llu of %llu (truncated?)", e->name, j,
                               e->count);
            goto done;
        }
    }
    return true;
done:
    return false;
}

bool mesh_check_ply(mesh_stream *s)
{
    int r = mesh_get_line(s);
    if (r < 0)
        return false;
    if (r == 0 || strcmp(s->ln, "ply") != 0)
        return mesh_fail_line(s, "not a PLY file: the first line must be 'ply'");
    ply_format fmt;
    ply_elem *elems;
    int nelems;
    if (!ply_read_header(s, &fmt, &elems, &nelems))
        return false;
    unsigned long long nv = ply_vertex_count(s, elems, nelems);
    s->vertices = nv;
    for (int i = 0; i < nelems; i++)
        if (strcmp(elems[i].name, "face") == 0) s->faces += elems[i].count;
    bool ok = nv > 0 && ply_check_body(s, fmt, elems, nelems, nv);
    free(elems);
    return ok;
}
