/* The OBJ checker (mesh_check.h).
 *
 * Compiled for the x86-64 baseline. */

#include "build/mesh_check.h"

#include <stdlib.h>

/* The numbers after a v, vt or vn keyword: finite decimal reals, as many
 * as Assimp 5.2 reads. It drops a vertex of 5 numbers (or 7, or 2)
 * without a word, so the faces after it point at the wrong vertices, and
 * throws on a texture coordinate of 1 or 4 numbers, leaking the mesh
 * (found by fuzz_mesh_obj). A w of 0 it divides by. */
typedef enum { OBJ_V, OBJ_VT, OBJ_VN } obj_kind;

static bool obj_numbers(mesh_stream *s, const char **cur, obj_kind kind)
{
    static const char *const what[] = {"vertex", "texture coordinate", "normal"};
    static const char *const counts[] = {"3, 4 or 6", "2 or 3", "3"};
    double x[7];
    unsigned n = 0;
    mesh_tok t;
    char b[48];
    while (next_tok(cur, &t)) {
        if (n == 7)
            return mesh_fail_line(s, "%s with more than 6 numbers", what[kind]);
        int r = mesh_parse_real(t, &x[n]);
        if (r == NUM_BAD)
            return mesh_fail_line(s, "bad number '%s' in a %s", mesh_tok_str(t, b), what[kind]);
        if (r == NUM_NONFINITE)
            return mesh_fail_line(s, "%s component '%s' is not a finite float", what[kind],
                                  mesh_tok_str(t, b));
        n++;
    }
    bool ok = kind == OBJ_V ? n == 3 || n == 4 || n == 6 : kind == OBJ_VT ? n == 2 || n == 3 : n == 3;
    if (kind == OBJ_V && n < 3)
        return mesh_fail_line(s, "vertex has fewer than 3 coordinates");
    if (!ok)
        return mesh_fail_line(s, "%s with %u numbers (Assimp reads %s)", what[kind], n, counts[kind]);
    if (kind == OBJ_V && n == 4 && x[3] == 0.0)
        return mesh_fail_line(s, "vertex with w = 0");
    return true;
}

/* The indices of a face, line or point into one kind of element: nonzero;
 * negative ones count back from the last element defined so far, positive
 * ones may name elements defined further down, so their range is checked
 * at the end. */
typedef struct obj_ref {
    unsigned long long count, max; /* elements defined so far; largest index */
    unsigned long max_line;
    const char *what;
} obj_ref;

static bool obj_index(mesh_stream *s, mesh_tok field, mesh_tok whole, obj_ref *ref)
{
    long long i;
    char b[48];
    if (mesh_parse_int(field, &i) != NUM_OK)
        return mesh_fail_line(s, "bad %s index in '%s'", ref->what, mesh_tok_str(whole, b));
    /* Assimp 5.2 steps over as many characters as the value has digits, so
     * a '+' or a leading zero leaves digits behind that it reads as more
     * indices ("f 1 2 +4" is the quad 1 2 4 4). */
    size_t sign = field.p[0] == '-';
    if (field.p[0] == '+' || (field.n > sign + 1 && field.p[sign] == '0'))
        return mesh_fail_line(s, "%s index '%s' with a '+' or a leading zero (Assimp reads it as "
                                 "several indices)",
                              ref->what, mesh_tok_str(whole, b));
    if (i == 0)
        return mesh_fail_line(s, "%s index 0 in '%s' (OBJ indices start at 1)", ref->what,
                              mesh_tok_str(whole, b));
    if (i < 0 && (unsigned long long)(-i) > ref->count)
        return mesh_fail_line(s,
                              "relative %s index -%llu reaches before the first one (%llu defined "
                              "so far)",
                              ref->what, (unsigned long long)(-i), ref->count);
    if (i > 0 && (unsigned long long)i > ref->max) {
        ref->max = (unsigned long long)i;
        ref->max_line = s->line;
    }
    return true;
}

static bool obj_range(mesh_stream *s, const obj_ref *ref)
{
    if (ref->max <= ref->count)
        return true;
    s->line = ref->max_line;
    return mesh_fail_line(s, "%s index %llu out of range (the file has %llu)", ref->what, ref->max,
                          ref->count);
}

/* The next line as Assimp's OBJ reader sees it: a backslash that ends a
 * line is dropped with the line break, and the next line follows with no
 * blank between ("v 1 \\" then "2 3" is "v 1 2 3"), before comments are
 * cut. Messages name the last of the joined lines. 1: a line is in s->ln;
 * 0: end of file; -1: error (message set). */
static int obj_get_line(mesh_stream *s, char **held, size_t *held_cap)
{
    int r = mesh_get_line(s);
    while (r > 0 && s->ln_len > 0 && s->ln[s->ln_len - 1] == '\\') {
        size_t keep = s->ln_len - 1;
        if (keep + 1 > *held_cap) {
            char *p = realloc(*held, keep + 1);
            if (!p) {
                lanes_error_set(s->err, LANES_ERR_OUT_OF_MEMORY, "%s: out of memory reading a line", s->path);
                return -1;
            }
            *held = p;
            *held_cap = keep + 1;
        }
        memcpy(*held, s->ln, keep);
        r = mesh_get_line(s);
        if (r == 0) {
            mesh_fail_line(s, "the last line ends in a line continuation '\\'");
            return -1;
        }
        if (r < 0) return r;
        if (keep + s->ln_len + 1 > MAX_LINE) {
            mesh_fail_line(s, "line longer than %u bytes", MAX_LINE);
            return -1;
        }
        if (keep + s->ln_len + 1 > s->ln_cap) {
            char *p = realloc(s->ln, keep + s->ln_len + 1);
            if (!p) {
                lanes_error_set(s->err, LANES_ERR_OUT_OF_MEMORY, "%s: out of memory reading a line", s->path);
                return -1;
            }
            s->ln = p;
            s->ln_cap = keep + s->ln_len + 1;
        }
        memmove(s->ln + keep, s->ln, s->ln_len + 1);
        memcpy(s->ln, *held, keep);
        s->ln_len += keep;
    }
    return r;
}

static bool check_obj(mesh_stream *s, char **held, size_t *held_cap)
{
    obj_ref v = {0, 0, 0, "vertex"}, vt = {0, 0, 0, "texture coordinate"},
            vn = {0, 0, 0, "normal"};
    int r;
    while ((r = obj_get_line(s, held, held_cap)) > 0) {
        char *hash = strchr(s->ln, '#');
        if (hash)
            *hash = '\0';
        const char *cur = s->ln;
        mesh_tok kw;
        char b[48];
        if (!next_tok(&cur, &kw))
            continue;
        bool geometry = strchr("vflp", kw.p[0]) != NULL;
        /* Assimp skips a line that starts with a blank: an indented vertex
         * or face would be lost, or shift every index after it. */
        if (geometry && kw.p != s->ln)
            return mesh_fail_line(s, "indented '%s' statement (Assimp ignores lines that start with "
                                     "a blank)",
                                  mesh_tok_str(kw, b));
        if (tok_is(kw, "v")) {
            if (!obj_numbers(s, &cur, OBJ_V))
                return false;
            if (++v.count > MAX_VERTICES)
                return mesh_fail_line(s, "more than %llu vertices", MAX_VERTICES);
        } else if (kw.p[0] == 'v' && kw.n >= 2 && (kw.p[1] == 't' || kw.p[1] == 'n')) {
            /* Assimp takes every "vt..." for a texture coordinate and every
             * "vn..." for a normal. */
            bool tex = kw.p[1] == 't';
            if (kw.n != 2)
                return mesh_fail_line(s, "unsupported OBJ statement '%s'", mesh_tok_str(kw, b));
            if (!obj_numbers(s, &cur, tex ? OBJ_VT : OBJ_VN))
                return false;
            (tex ? &vt : &vn)->count++;
        } else if (kw.p[0] == 'f' || kw.p[0] == 'l' || kw.p[0] == 'p') {
            /* Assimp reads every statement starting with f, l or p as a
             * face, line or point ("lod 1" too) and fails on it, so such
             * statements must be exactly that. */
            if (kw.n != 1)
                return mesh_fail_line(s, "unsupported OBJ statement '%s'", mesh_tok_str(kw, b));
            mesh_tok t;
            size_t count = 0;
            while (next_tok(&cur, &t)) {
                /* v, v/vt, v//vn or v/vt/vn. Assimp 5.2 throws on an index
                 * of texture coordinates or normals out of range and leaks
                 * the mesh (found by fuzz_mesh_obj), so all three are
                 * checked, not only the vertex. */
                obj_ref *refs[3] = {&v, &vt, &vn};
                const char *p = t.p, *end = t.p + t.n;
                for (int k = 0; k < 3 && p <= end; k++) {
                    const char *slash = memchr(p, '/', (size_t)(end - p));
                    mesh_tok f = {p, (size_t)((slash ? slash : end) - p)};
                    if (f.n > 0 || k == 0) {
                        if (!obj_index(s, f, t, refs[k]))
                            return false;
                    }
                    if (!slash) {
                        p = end + 1;
                        break;
                    }
                    p = slash + 1;
                    if (k == 2)
                        return mesh_fail_line(s, "bad index '%s' (at most v/vt/vn)", mesh_tok_str(t, b));
                }
                if (++count > MAX_POLYGON)
                    return mesh_fail_line(s, "face with more than %d vertices", MAX_POLYGON);
            }
            if (kw.p[0] == 'l' && count < 2)
                return mesh_fail_line(s, "a line element needs at least 2 vertices");
            /* Assimp's OBJ reader makes a vertex per face corner */
            s->faces++;
            s->vertices += count;
        }
    }
    if (r < 0)
        return false;
    /* OBJ lets a face name a vertex defined further down, so the range of
     * positive indices is only known at the end. */
    if (!obj_range(s, &v) || !obj_range(s, &vt) || !obj_range(s, &vn))
        return false;
    if (v.count == 0) {
        lanes_error_set(s->err, LANES_ERR_BAD_INPUT, "%s: no vertices", s->path);
        return false;
    }
    s->vertices += v.count;
    return true;
}

bool mesh_check_obj(mesh_stream *s)
{
    char *held = NULL;
    size_t held_cap = 0;
    bool ok = check_obj(s, &held, &held_cap);
    free(held);
    return ok;
}
