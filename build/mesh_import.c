/* Mesh files: a streaming validator for the text and simple binary formats,
 * then Assimp, then checks on what Assimp returns. See mesh_import.h for
 * why all three are needed.
 *
 * Compiled for the x86-64 baseline. */
#define _POSIX_C_SOURCE 200809L /* stat, for "is a directory" before Assimp sees it */

#include "build/mesh_import.h"

#include <assimp/cfileio.h>
#include <assimp/cimport.h>
#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <cjson/cJSON.h>

#include <ctype.h>
#include <errno.h>
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* Bounds on what a sane mesh file holds; past them a count is a corrupt
 * header, not a mesh, and we refuse before anything is allocated. */
#define MAX_VERTICES ((unsigned long long)UINT32_MAX)
#define MAX_POLYGON 65536    /* vertices of one face */
#define MAX_OFF_POLYGON 9    /* what Assimp 5.2's OFF reader keeps */
#define MAX_LINE (64u << 20) /* bytes of one text line */
#define MAX_NODE_DEPTH 256   /* Assimp node hierarchy */

/* ---- a buffered reader that knows its line number and byte offset ---- */

typedef struct stream {
    FILE *f;
    const char *path;
    lanes_error *err;
    unsigned char buf[1 << 16];
    size_t pos, len;
    unsigned long long base; /* file offset of buf[0] */
    bool eof, ioerr;
    unsigned long line; /* number of the line last returned */
    char *ln;           /* that line, NUL-terminated, without \r\n */
    size_t ln_len, ln_cap;
} stream;

static bool fill(stream *s)
{
    if (s->pos < s->len)
        return true;
    if (s->eof)
        return false;
    s->base += s->len;
    s->pos = 0;
    s->len = fread(s->buf, 1, sizeof s->buf, s->f);
    if (s->len == 0) {
        s->eof = true;
        s->ioerr = ferror(s->f) != 0;
        return false;
    }
    return true;
}

static unsigned long long stream_offset(const stream *s)
{
    return s->base + s->pos;
}

#if defined(__GNUC__)
#define PRINTF_LIKE(f, a) __attribute__((format(printf, f, a)))
#else
#define PRINTF_LIKE(f, a)
#endif

static bool fail_line(stream *s, const char *fmt, ...) PRINTF_LIKE(2, 3);
static bool fail_byte(stream *s, unsigned long long at, const char *fmt, ...) PRINTF_LIKE(3, 4);

/* "file: line N: what" for the text formats. */
static bool fail_line(stream *s, const char *fmt, ...)
{
    char what[400];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    lanes_error_set(s->err, "%s: line %lu: %s", s->path, s->line, what);
    return false;
}

/* "file: byte N: what" for binary data, which has no lines. */
static bool fail_byte(stream *s, unsigned long long at, const char *fmt, ...)
{
    char what[400];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    lanes_error_set(s->err, "%s: byte %llu: %s", s->path, at, what);
    return false;
}

/* 1: a line is in s->ln; 0: end of file; -1: error (message set). */
static int get_line(stream *s)
{
    s->ln_len = 0;
    bool any = false;
    while (fill(s)) {
        any = true;
        const unsigned char *start = s->buf + s->pos;
        size_t avail = s->len - s->pos;
        const unsigned char *nl = memchr(start, '\n', avail);
        size_t take = nl ? (size_t)(nl - start) : avail;
        if (s->ln_len + take + 1 > s->ln_cap) {
            if (s->ln_len + take + 1 > MAX_LINE) {
                s->line++;
                fail_line(s, "line longer than %u bytes", MAX_LINE);
                return -1;
            }
            size_t cap = s->ln_cap ? s->ln_cap : 256;
            while (cap < s->ln_len + take + 1)
                cap *= 2;
            char *p = realloc(s->ln, cap);
            if (!p) {
                lanes_error_set(s->err, "%s: out of memory reading a line", s->path);
                return -1;
            }
            s->ln = p;
            s->ln_cap = cap;
        }
        memcpy(s->ln + s->ln_len, start, take);
        s->ln_len += take;
        s->pos += take + (nl ? 1 : 0);
        if (nl)
            break;
    }
    if (s->ioerr) {
        lanes_error_set(s->err, "%s: read error: %s", s->path, strerror(errno));
        return -1;
    }
    if (!any)
        return 0;
    s->line++;
    if (s->ln_len > 0 && s->ln[s->ln_len - 1] == '\r')
        s->ln_len--;
    s->ln[s->ln_len] = '\0';
    /* Assimp's text readers end a line at NUL, CR and FF and take VT for
     * part of a token; this validator would read past a NUL, and treats
     * VT and FF as blanks. Where the two disagree about the tokens, the
     * file that passed here is not the file Assimp reads: a VT before an
     * OFF face made Assimp 5.2 crash, a NUL inside a PLY number made it
     * leak (both found by the fuzzers). No mesh needs these bytes. */
    for (size_t i = 0; i < s->ln_len; i++) {
        unsigned char c = (unsigned char)s->ln[i];
        if (c == '\0' || c == '\r' || c == '\v' || c == '\f') {
            if (c == '\r')
                fail_line(s, "carriage return at column %zu (old Mac line endings are not "
                             "supported)",
                          i + 1);
            else
                fail_line(s, "control character 0x%02x at column %zu (binary data in a text "
                             "file?)",
                          c, i + 1);
            return -1;
        }
    }
    return 1;
}

static bool get_bytes(stream *s, void *dst, size_t n)
{
    unsigned char *d = dst;
    while (n > 0) {
        if (!fill(s))
            return false;
        size_t k = s->len - s->pos < n ? s->len - s->pos : n;
        memcpy(d, s->buf + s->pos, k);
        s->pos += k;
        d += k;
        n -= k;
    }
    return true;
}

/* ---- tokens and numbers ---- */

typedef struct tok {
    const char *p;
    size_t n;
} tok;

static bool is_space(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

static bool next_tok(const char **cur, tok *t)
{
    const char *p = *cur;
    while (*p && is_space(*p))
        p++;
    if (!*p)
        return false;
    const char *q = p;
    while (*q && !is_space(*q))
        q++;
    t->p = p;
    t->n = (size_t)(q - p);
    *cur = q;
    return true;
}

static bool tok_is(tok t, const char *w)
{
    return t.n == strlen(w) && memcmp(t.p, w, t.n) == 0;
}

/* Printable form of a token for messages, cut short. */
static const char *tok_str(tok t, char out[48])
{
    size_t n = t.n < 40 ? t.n : 40;
    for (size_t i = 0; i < n; i++)
        out[i] = isprint((unsigned char)t.p[i]) ? t.p[i] : '?';
    strcpy(out + n, t.n > n ? "..." : "");
    return out;
}

enum { NUM_OK, NUM_BAD, NUM_NONFINITE };

/* Decimal reals only. strtod would also take hex floats and "nan(...)",
 * which Assimp's own number reader does not, so the two would disagree
 * about what the file holds. Also non-finite as a float counts as
 * non-finite: the scene stores floats. (strtod follows the C locale; the
 * library never calls setlocale.) */
static int parse_real(tok t, double *out)
{
    size_t i = 0;
    if (i < t.n && (t.p[i] == '+' || t.p[i] == '-'))
        i++;
    if (t.n - i >= 3) {
        char a = (char)tolower((unsigned char)t.p[i]), b = (char)tolower((unsigned char)t.p[i + 1]),
             c = (char)tolower((unsigned char)t.p[i + 2]);
        if ((a == 'n' && b == 'a' && c == 'n') || (a == 'i' && b == 'n' && c == 'f'))
            return NUM_NONFINITE;
    }
    if (t.n == 0 || t.n >= 64)
        return NUM_BAD;
    bool digit = false;
    for (size_t k = 0; k < t.n; k++) {
        char c = t.p[k];
        if (c >= '0' && c <= '9')
            digit = true;
        else if (c != '.' && c != 'e' && c != 'E' && c != '+' && c != '-')
            return NUM_BAD;
    }
    if (!digit)
        return NUM_BAD;
    char buf[64];
    memcpy(buf, t.p, t.n);
    buf[t.n] = '\0';
    char *end;
    double v = strtod(buf, &end);
    if (end != buf + t.n)
        return NUM_BAD;
    *out = v;
    if (!isfinite(v) || fabs(v) > FLT_MAX)
        return NUM_NONFINITE;
    return NUM_OK;
}

/* Decimal integers; anything past 18 digits is out of every range here. */
static int parse_int(tok t, long long *out)
{
    size_t i = 0;
    bool neg = false;
    if (i < t.n && (t.p[i] == '+' || t.p[i] == '-'))
        neg = t.p[i++] == '-';
    if (i == t.n || t.n - i > 18)
        return NUM_BAD;
    long long v = 0;
    for (; i < t.n; i++) {
        if (t.p[i] < '0' || t.p[i] > '9')
            return NUM_BAD;
        v = v * 10 + (t.p[i] - '0');
    }
    *out = neg ? -v : v;
    return NUM_OK;
}

/* Unsigned decimal integers, digits only: Assimp reads OFF's integers and
 * PLY's unsigned ones with strtoul10, which stops at a sign, so "+1" is 0
 * to it and the rest of the line shifts (a "+1" face count made Assimp 5.2
 * crash, found by fuzz_mesh_off). */
static int parse_uint(tok t, long long *out)
{
    if (t.n == 0 || t.p[0] == '+' || t.p[0] == '-')
        return NUM_BAD;
    return parse_int(t, out);
}

/* A real in the shape Assimp's fast_atoreal_move reads whole, for the
 * formats it parses as one stream (OFF, PLY, STL) rather than word by word
 * (OBJ): a point must be followed by a digit ("4." leaves the point for
 * the next number, which then fails: Assimp 5.2 throws and leaks the PLY
 * mesh, found by fuzz_mesh_ply), and at most 18 digits before the point
 * or in the exponent (more overflow its 64-bit reader, which then stops
 * without moving on). */
static int parse_real_stream(tok t, double *out)
{
    size_t i = 0, n = t.n, digits = 0;
    if (i < n && (t.p[i] == '+' || t.p[i] == '-'))
        i++;
    if (i < n && !(t.p[i] >= '0' && t.p[i] <= '9') && t.p[i] != '.')
        return parse_real(t, out); /* nan, inf or a bad token */
    while (i < n && t.p[i] >= '0' && t.p[i] <= '9')
        i++, digits++;
    if (digits > 18)
        return NUM_BAD;
    if (i < n && t.p[i] == '.') {
        if (i + 1 >= n || !(t.p[i + 1] >= '0' && t.p[i + 1] <= '9'))
            return NUM_BAD;
        for (i++; i < n && t.p[i] >= '0' && t.p[i] <= '9'; i++)
            digits++;
    }
    if (digits == 0)
        return NUM_BAD;
    if (i < n && (t.p[i] == 'e' || t.p[i] == 'E')) {
        size_t e = 0;
        if (++i < n && (t.p[i] == '+' || t.p[i] == '-'))
            i++;
        while (i < n && t.p[i] >= '0' && t.p[i] <= '9')
            i++, e++;
        if (e == 0 || e > 18)
            return NUM_BAD;
    }
    return i == n ? parse_real(t, out) : NUM_BAD;
}

/* Reads three coordinates of a vertex from *cur. */
static bool read_xyz(stream *s, const char **cur, const char *what)
{
    for (int k = 0; k < 3; k++) {
        tok t;
        char b[48];
        double v;
        if (!next_tok(cur, &t))
            return fail_line(s, "%s has fewer than 3 coordinates", what);
        int r = parse_real_stream(t, &v);
        if (r == NUM_BAD)
            return fail_line(s, "bad number '%s' in a vertex", tok_str(t, b));
        if (r == NUM_NONFINITE)
            return fail_line(s, "vertex coordinate '%s' is not a finite float", tok_str(t, b));
    }
    return true;
}

/* ---- OBJ ---- */

/* The numbers after a v, vt or vn keyword: finite decimal reals, as many
 * as Assimp 5.2 reads. It drops a vertex of 5 numbers (or 7, or 2)
 * without a word, so the faces after it point at the wrong vertices, and
 * throws on a texture coordinate of 1 or 4 numbers, leaking the mesh
 * (found by fuzz_mesh_obj). A w of 0 it divides by. */
typedef enum { OBJ_V, OBJ_VT, OBJ_VN } obj_kind;

static bool obj_numbers(stream *s, const char **cur, obj_kind kind)
{
    static const char *const what[] = {"vertex", "texture coordinate", "normal"};
    static const char *const counts[] = {"3, 4 or 6", "2 or 3", "3"};
    double x[7];
    unsigned n = 0;
    tok t;
    char b[48];
    while (next_tok(cur, &t)) {
        if (n == 7)
            return fail_line(s, "%s with more than 6 numbers", what[kind]);
        int r = parse_real(t, &x[n]);
        if (r == NUM_BAD)
            return fail_line(s, "bad number '%s' in a %s", tok_str(t, b), what[kind]);
        if (r == NUM_NONFINITE)
            return fail_line(s, "%s component '%s' is not a finite float", what[kind],
                             tok_str(t, b));
        n++;
    }
    bool ok = kind == OBJ_V ? n == 3 || n == 4 || n == 6 : kind == OBJ_VT ? n == 2 || n == 3 : n == 3;
    if (kind == OBJ_V && n < 3)
        return fail_line(s, "vertex has fewer than 3 coordinates");
    if (!ok)
        return fail_line(s, "%s with %u numbers (Assimp reads %s)", what[kind], n, counts[kind]);
    if (kind == OBJ_V && n == 4 && x[3] == 0.0)
        return fail_line(s, "vertex with w = 0");
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

static bool obj_index(stream *s, tok field, tok whole, obj_ref *ref)
{
    long long i;
    char b[48];
    if (parse_int(field, &i) != NUM_OK)
        return fail_line(s, "bad %s index in '%s'", ref->what, tok_str(whole, b));
    if (i == 0)
        return fail_line(s, "%s index 0 in '%s' (OBJ indices start at 1)", ref->what,
                         tok_str(whole, b));
    if (i < 0 && (unsigned long long)(-i) > ref->count)
        return fail_line(s,
                         "relative %s index -%llu reaches before the first one (%llu defined "
                         "so far)",
                         ref->what, (unsigned long long)(-i), ref->count);
    if (i > 0 && (unsigned long long)i > ref->max) {
        ref->max = (unsigned long long)i;
        ref->max_line = s->line;
    }
    return true;
}

static bool obj_range(stream *s, const obj_ref *ref)
{
    if (ref->max <= ref->count)
        return true;
    s->line = ref->max_line;
    return fail_line(s, "%s index %llu out of range (the file has %llu)", ref->what, ref->max,
                     ref->count);
}

static bool check_obj(stream *s)
{
    obj_ref v = {0, 0, 0, "vertex"}, vt = {0, 0, 0, "texture coordinate"},
            vn = {0, 0, 0, "normal"};
    int r;
    while ((r = get_line(s)) > 0) {
        char *hash = strchr(s->ln, '#');
        if (hash)
            *hash = '\0';
        const char *cur = s->ln;
        tok kw;
        char b[48];
        if (!next_tok(&cur, &kw))
            continue;
        bool geometry = strchr("vflp", kw.p[0]) != NULL;
        /* Assimp skips a line that starts with a blank: an indented vertex
         * or face would be lost, or shift every index after it. */
        if (geometry && kw.p != s->ln)
            return fail_line(s, "indented '%s' statement (Assimp ignores lines that start with "
                                "a blank)",
                             tok_str(kw, b));
        if (tok_is(kw, "v")) {
            if (!obj_numbers(s, &cur, OBJ_V))
                return false;
            if (++v.count > MAX_VERTICES)
                return fail_line(s, "more than %llu vertices", MAX_VERTICES);
        } else if (kw.p[0] == 'v' && kw.n >= 2 && (kw.p[1] == 't' || kw.p[1] == 'n')) {
            /* Assimp takes every "vt..." for a texture coordinate and every
             * "vn..." for a normal. */
            bool tex = kw.p[1] == 't';
            if (kw.n != 2)
                return fail_line(s, "unsupported OBJ statement '%s'", tok_str(kw, b));
            if (!obj_numbers(s, &cur, tex ? OBJ_VT : OBJ_VN))
                return false;
            (tex ? &vt : &vn)->count++;
        } else if (kw.p[0] == 'f' || kw.p[0] == 'l' || kw.p[0] == 'p') {
            /* Assimp reads every statement starting with f, l or p as a
             * face, line or point ("lod 1" too) and fails on it, so such
             * statements must be exactly that. */
            if (kw.n != 1)
                return fail_line(s, "unsupported OBJ statement '%s'", tok_str(kw, b));
            tok t;
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
                    tok f = {p, (size_t)((slash ? slash : end) - p)};
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
                        return fail_line(s, "bad index '%s' (at most v/vt/vn)", tok_str(t, b));
                }
                if (++count > MAX_POLYGON)
                    return fail_line(s, "face with more than %d vertices", MAX_POLYGON);
            }
            if (kw.p[0] == 'l' && count < 2)
                return fail_line(s, "a line element needs at least 2 vertices");
        }
    }
    if (r < 0)
        return false;
    /* OBJ lets a face name a vertex defined further down, so the range of
     * positive indices is only known at the end. */
    if (!obj_range(s, &v) || !obj_range(s, &vt) || !obj_range(s, &vn))
        return false;
    if (v.count == 0) {
        lanes_error_set(s->err, "%s: no vertices", s->path);
        return false;
    }
    return true;
}

/* ---- OFF ---- */

/* Next line that is neither blank nor a comment; *cur at its start. */
static int off_line(stream *s, const char **cur)
{
    int r;
    while ((r = get_line(s)) > 0) {
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
static int off_body_line(stream *s, const char **cur, const char *what)
{
    int r;
    while ((r = get_line(s)) > 0) {
        if (s->ln_len == 0)
            continue;
        const char *p = s->ln;
        while (*p && is_space(*p))
            p++;
        if (!*p || *p == '#') {
            fail_line(s, "%s inside the %s list (Assimp cannot read OFF files with these; "
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

static bool is_off_keyword(tok t)
{
    /* [ST][C][N]OFF; 4OFF and nOFF are other dimensions, not meshes. */
    if (t.n < 3 || t.n > 6 || memcmp(t.p + t.n - 3, "OFF", 3) != 0)
        return false;
    for (size_t i = 0; i + 3 < t.n; i++)
        if (!strchr("STCN", t.p[i]))
            return false;
    return true;
}

static bool check_off(stream *s)
{
    const char *cur;
    tok t;
    int r = off_line(s, &cur);
    if (r < 0)
        return false;
    if (r == 0 || !next_tok(&cur, &t) || !is_off_keyword(t)) {
        char b[48];
        return fail_line(s, "not an OFF file: expected 'OFF', found '%s'",
                         r == 0 ? "end of file" : tok_str(t, b));
    }
    long long counts[2];
    int have = 0;
    while (have < 2) {
        if (!next_tok(&cur, &t)) {
            r = off_line(s, &cur);
            if (r < 0)
                return false;
            if (r == 0)
                return fail_line(s, "file ends before the vertex and face counts");
            continue;
        }
        char b[48];
        if (have == 0 && tok_is(t, "BINARY"))
            return fail_line(s, "binary OFF is not supported");
        if (parse_uint(t, &counts[have]) != NUM_OK)
            return fail_line(s, "bad count '%s' in the OFF header", tok_str(t, b));
        have++;
    }
    unsigned long long nv = (unsigned long long)counts[0], nf = (unsigned long long)counts[1];
    if (nv == 0 || nv > MAX_VERTICES)
        return fail_line(s, "vertex count %llu out of range [1, %llu]", nv, MAX_VERTICES);
    if (nf == 0)
        return fail_line(s, "no faces (a point cloud is not a mesh)");
    if (nf > LANES_SCENE_MAX_TRIANGLES)
        return fail_line(s, "face count %llu exceeds the limit of %llu", nf,
                         (unsigned long long)LANES_SCENE_MAX_TRIANGLES);
    for (unsigned long long v = 0; v < nv; v++) {
        r = off_body_line(s, &cur, "vertex");
        if (r < 0)
            return false;
        if (r == 0)
            return fail_line(s, "file ends after %llu of %llu vertices (truncated?)", v, nv);
        if (!read_xyz(s, &cur, "vertex"))
            return false;
    }
    for (unsigned long long f = 0; f < nf; f++) {
        r = off_body_line(s, &cur, "face");
        if (r < 0)
            return false;
        if (r == 0)
            return fail_line(s, "file ends after %llu of %llu faces (truncated?)", f, nf);
        long long n, i;
        char b[48];
        if (!next_tok(&cur, &t) || parse_uint(t, &n) != NUM_OK)
            return fail_line(s, "bad face: expected a vertex count, found '%s'", tok_str(t, b));
        /* Assimp 5.2 drops OFF faces of more than 9 vertices without a
         * word; refused rather than lost. */
        if (n < 1 || n > MAX_OFF_POLYGON)
            return fail_line(s, "face with %lld vertices (OFF faces here have 1 to %d)", n,
                             MAX_OFF_POLYGON);
        for (long long k = 0; k < n; k++) {
            if (!next_tok(&cur, &t))
                return fail_line(s, "face lists %llu of its %llu vertex indices",
                                 (unsigned long long)k, (unsigned long long)n);
            if (parse_uint(t, &i) != NUM_OK)
                return fail_line(s, "bad vertex index '%s'", tok_str(t, b));
            if ((unsigned long long)i >= nv)
                return fail_line(s, "vertex index %s out of range (the file has %llu vertices)",
                                 tok_str(t, b), nv);
        }
    }
    return true;
}

/* ---- PLY ---- */

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

static int ply_type(tok t)
{
    for (int i = 0; i < (int)(sizeof ply_types / sizeof ply_types[0]); i++)
        if (tok_is(t, ply_types[i].name) || tok_is(t, ply_types[i].alias))
            return i;
    return -1;
}

/* One binary value as a double (exact for every integer type here). */
static bool ply_read_bin(stream *s, ply_format fmt, int type, double *out)
{
    unsigned char b[8];
    int n = ply_types[type].size;
    if (!get_bytes(s, b, (size_t)n))
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
static int ply_start_line(stream *s, ply_cursor *c)
{
    int r;
    while ((r = get_line(s)) > 0) {
        c->cur = s->ln;
        tok t;
        const char *peek = s->ln;
        if (next_tok(&peek, &t))
            return 1;
    }
    return r;
}

/* Whether token t names the element stored as `stored` (cut to size - 1
 * characters; two long names that agree that far count as the same). */
static bool ply_same_name(tok t, const char *stored, size_t size)
{
    if (t.n < size) return tok_is(t, stored);
    return strlen(stored) == size - 1 && memcmp(t.p, stored, size - 1) == 0;
}

static bool check_ply(stream *s)
{
    int r = get_line(s);
    if (r < 0)
        return false;
    if (r == 0 || strcmp(s->ln, "ply") != 0)
        return fail_line(s, "not a PLY file: the first line must be 'ply'");
    ply_format fmt = PLY_ASCII;
    bool have_format = false;
    ply_elem *elems = NULL;
    int nelems = 0;
    bool ok = false;
    for (;;) {
        r = get_line(s);
        if (r < 0)
            goto done;
        if (r == 0) {
            fail_line(s, "the header has no 'end_header' (truncated?)");
            goto done;
        }
        const char *cur = s->ln;
        tok kw, t, u, v;
        char b[48];
        bool blank = !next_tok(&cur, &kw);
        /* Assimp 5.2 reads the format from the line after "ply" and from
         * no other: a comment before it is an error to Assimp, and a
         * second format line, which this check used to follow, made the
         * two read different encodings (found by fuzz_mesh_ply). */
        if (!have_format && (blank || !tok_is(kw, "format"))) {
            fail_line(s, "the line after 'ply' must be 'format ascii|binary_little_endian|"
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
                fail_line(s, "a second 'format' line");
                goto done;
            }
            if (!next_tok(&cur, &t) || !next_tok(&cur, &u) || !tok_is(u, "1.0") ||
                next_tok(&cur, &v)) {
                fail_line(s, "expected 'format ascii|binary_little_endian|binary_big_endian "
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
                fail_line(s, "unknown PLY format '%s'", tok_str(t, b));
                goto done;
            }
            have_format = true;
        } else if (tok_is(kw, "element")) {
            long long n;
            if (!next_tok(&cur, &t) || !next_tok(&cur, &u) || parse_uint(u, &n) != NUM_OK) {
                fail_line(s, "'element' needs a name and a count");
                goto done;
            }
            if (nelems == 32) {
                fail_line(s, "more than 32 elements");
                goto done;
            }
            /* A name declared twice is no PLY file's intent, and Assimp 5.2
             * leaks on it (a second 'face' element: found by
             * fuzz_mesh_ply_binary). */
            for (int i = 0; i < nelems; i++)
                if (ply_same_name(t, elems[i].name, sizeof elems[i].name)) {
                    fail_line(s, "element '%s' declared twice", elems[i].name);
                    goto done;
                }
            /* Assimp 5.2 keeps only the first triangle of a file's strips
             * and leaks the index arrays of the others (found by
             * fuzz_mesh_ply): silently wrong geometry, so refused. */
            if (tok_is(t, "tristrips") && n > 0) {
                fail_line(s, "element 'tristrips' is not supported (Assimp 5.2 drops all but "
                             "the first triangle of the strips); store faces instead");
                goto done;
            }
            ply_elem *e = realloc(elems, (size_t)(nelems + 1) * sizeof *e);
            if (!e) {
                lanes_error_set(s->err, "%s: out of memory", s->path);
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
                fail_line(s, "'property' before any 'element'");
                goto done;
            }
            ply_elem *e = &elems[nelems - 1];
            if (e->nprops == 64) {
                fail_line(s, "more than 64 properties in element '%s'", e->name);
                goto done;
            }
            ply_prop *p = &e->props[e->nprops];
            if (!next_tok(&cur, &t)) {
                fail_line(s, "'property' without a type");
                goto done;
            }
            tok name;
            if (tok_is(t, "list")) {
                if (!next_tok(&cur, &u) || !next_tok(&cur, &v) || !next_tok(&cur, &name) ||
                    (p->count_type = ply_type(u)) < 0 || (p->type = ply_type(v)) < 0 ||
                    ply_types[p->count_type].is_float) {
                    fail_line(s, "bad list property");
                    goto done;
                }
            } else {
                p->count_type = -1;
                if ((p->type = ply_type(t)) < 0 || !next_tok(&cur, &name)) {
                    fail_line(s, "bad property type '%s'", tok_str(t, b));
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
            fail_line(s, "unknown header keyword '%s'", tok_str(kw, b));
            goto done;
        }
    }
    if (!have_format) {
        fail_line(s, "the header has no 'format' line");
        goto done;
    }
    unsigned long long nv = 0;
    bool have_vertex = false, have_faces = false;
    for (int i = 0; i < nelems; i++) {
        ply_elem *e = &elems[i];
        if (strcmp(e->name, "vertex") == 0) {
            int roles = 0;
            for (int k = 0; k < e->nprops; k++)
                roles |= e->props[k].role ? 1 << e->props[k].role : 0;
            if ((roles & 14) != 14) {
                fail_line(s, "the vertex element lacks x, y or z");
                goto done;
            }
            nv = e->count;
            have_vertex = true;
        }
        if (strcmp(e->name, "face") == 0)
            have_faces = have_faces || e->count > 0;
    }
    if (!have_vertex || nv == 0 || nv > MAX_VERTICES) {
        fail_line(s, "the header declares %llu vertices (need 1 to %llu)", nv, MAX_VERTICES);
        goto done;
    }
    if (!have_faces) {
        fail_line(s, "the header declares no faces (a point cloud is not a mesh)");
        goto done;
    }
    ply_cursor c = {""};
    for (int i = 0; i < nelems; i++) {
        ply_elem *e = &elems[i];
        for (unsigned long long j = 0; j < e->count; j++) {
            if (fmt == PLY_ASCII) {
                r = ply_start_line(s, &c);
                if (r < 0)
                    goto done;
                if (r == 0)
                    goto truncated;
            }
            for (int k = 0; k < e->nprops; k++) {
                ply_prop *p = &e->props[k];
                unsigned long long at = stream_offset(s);
                double v;
                long long n = 1;
                tok t;
                char b[48];
                if (p->count_type >= 0) {
                    if (fmt == PLY_ASCII) {
                        if (!next_tok(&c.cur, &t))
                            goto short_line;
                        if ((ply_types[p->count_type].is_signed ? parse_int(t, &n)
                                                                : parse_uint(t, &n)) != NUM_OK) {
                            fail_line(s, "bad list length '%s'", tok_str(t, b));
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
                            fail_line(s, "list of length %s out of range", tok_str(t, b));
                        else
                            fail_byte(s, at, "list of length %lld out of range", n);
                        goto done;
                    }
                }
                for (long long m = 0; m < n; m++) {
                    at = stream_offset(s);
                    int num;
                    if (fmt == PLY_ASCII) {
                        if (!next_tok(&c.cur, &t))
                            goto short_line;
                        num = ply_types[p->type].is_float ? parse_real_stream(t, &v) : NUM_OK;
                        if (!ply_types[p->type].is_float) {
                            long long iv = 0;
                            num = ply_types[p->type].is_signed ? parse_int(t, &iv)
                                                               : parse_uint(t, &iv);
                            v = (double)iv;
                        }
                        if (num == NUM_BAD) {
                            fail_line(s, "bad number '%s' in element '%s'", tok_str(t, b), e->name);
                            goto done;
                        }
                    } else {
                        if (!ply_read_bin(s, fmt, p->type, &v))
                            goto truncated;
                        num = isfinite(v) && fabs(v) <= FLT_MAX ? NUM_OK : NUM_NONFINITE;
                    }
                    if (p->role >= 1 && p->role <= 3 && num != NUM_OK) {
                        if (fmt == PLY_ASCII)
                            fail_line(s, "vertex coordinate '%s' is not a finite float",
                                      tok_str(t, b));
                        else
                            fail_byte(s, at, "vertex %llu: coordinate is not a finite float", j);
                        goto done;
                    }
                    if (p->role == 4 && !(v >= 0 && v < (double)nv)) {
                        if (fmt == PLY_ASCII)
                            fail_line(s,
                                      "vertex index %s out of range (the file has %llu vertices)",
                                      tok_str(t, b), nv);
                        else
                            fail_byte(
                                s, at,
                                "face %llu: vertex index out of range (the file has %llu vertices)",
                                j, nv);
                        goto done;
                    }
                }
            }
            if (fmt == PLY_ASCII) {
                tok t;
                char b[48];
                if (next_tok(&c.cur, &t)) {
                    fail_line(s, "'%s' after the last property of element '%s' %llu (one "
                                 "element per line)",
                              tok_str(t, b), e->name, j);
                    goto done;
                }
            }
            continue;
        short_line:
            fail_line(s, "element '%s' %llu has fewer values than properties (one element per "
                         "line)",
                      e->name, j);
            goto done;
        truncated:
            if (fmt == PLY_ASCII)
                fail_line(s, "file ends in element '%s' %llu of %llu (truncated?)", e->name, j,
                          e->count);
            else
                fail_byte(s, stream_offset(s),
                          "file ends in element '%s' %llu of %llu (truncated?)", e->name, j,
                          e->count);
            goto done;
        }
    }
    ok = true;
done:
    free(elems);
    return ok;
}

/* ---- STL ---- */

static bool check_stl_binary(stream *s, unsigned long count)
{
    unsigned char rec[50];
    for (unsigned long i = 0; i < count; i++) {
        unsigned long long at = stream_offset(s);
        if (!get_bytes(s, rec, sizeof rec))
            return fail_byte(s, at, "file ends in triangle %lu of %lu (truncated?)", i, count);
        for (int k = 3; k < 12; k++) {
            uint32_t w = (uint32_t)rec[4 * k] | (uint32_t)rec[4 * k + 1] << 8 |
                         (uint32_t)rec[4 * k + 2] << 16 | (uint32_t)rec[4 * k + 3] << 24;
            float f;
            memcpy(&f, &w, 4);
            if (!isfinite(f))
                return fail_byte(s, at + 4 * (unsigned)k,
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
static bool stl_line_ends(stream *s, const char *cur, const char *what)
{
    tok t;
    char b[48];
    if (next_tok(&cur, &t))
        return fail_line(s, "unexpected '%s' after '%s'", tok_str(t, b), what);
    return true;
}

static bool check_stl_ascii(stream *s)
{
    bool in_facet = false, in_loop = false, had_loop = false;
    int nvert = 0;
    unsigned long long facets = 0;
    int r;
    while ((r = get_line(s)) > 0) {
        const char *cur = s->ln;
        tok kw;
        char b[48];
        if (!next_tok(&cur, &kw))
            continue;
        if (tok_is(kw, "solid") || tok_is(kw, "endsolid")) {
            if (in_facet)
                return fail_line(s, "'%s' inside a facet", tok_str(kw, b));
        } else if (tok_is(kw, "facet")) {
            if (in_facet)
                return fail_line(s, "'facet' before the previous one ended");
            /* Assimp rejects a malformed normal (and leaks the mesh it was
             * building), so it is checked here first. */
            tok t;
            if (!next_tok(&cur, &t) || !tok_is(t, "normal"))
                return fail_line(s, "expected 'facet normal nx ny nz'");
            for (int k = 0; k < 3; k++) {
                double v;
                if (!next_tok(&cur, &t) || parse_real_stream(t, &v) == NUM_BAD)
                    return fail_line(s, "expected 'facet normal nx ny nz'");
            }
            if (!stl_line_ends(s, cur, "facet normal nx ny nz"))
                return false;
            in_facet = true;
            had_loop = false;
            nvert = 0;
        } else if (tok_is(kw, "outer")) {
            tok t;
            if (!next_tok(&cur, &t) || !tok_is(t, "loop"))
                return fail_line(s, "expected 'outer loop'");
            if (!stl_line_ends(s, cur, "outer loop"))
                return false;
            if (!in_facet || in_loop || had_loop)
                return fail_line(s, "'outer loop' outside a facet, or a second one in it");
            in_loop = true;
        } else if (tok_is(kw, "vertex")) {
            if (!in_loop)
                return fail_line(s, "'vertex' outside a loop");
            if (!read_xyz(s, &cur, "vertex") || !stl_line_ends(s, cur, "vertex x y z"))
                return false;
            nvert++;
        } else if (tok_is(kw, "endloop")) {
            if (!stl_line_ends(s, cur, "endloop"))
                return false;
            if (!in_loop)
                return fail_line(s, "'endloop' without 'outer loop'");
            if (nvert != 3)
                return fail_line(s, "facet with %llu vertices (STL facets are triangles)",
                                 (unsigned long long)nvert);
            in_loop = false;
            had_loop = true;
        } else if (tok_is(kw, "endfacet")) {
            if (!stl_line_ends(s, cur, "endfacet"))
                return false;
            if (!in_facet || !had_loop)
                return fail_line(s, "'endfacet' without a complete facet");
            in_facet = false;
            facets++;
        } else {
            return fail_line(s, "unexpected '%s' in an ASCII STL file", tok_str(kw, b));
        }
    }
    if (r < 0)
        return false;
    if (in_facet)
        return fail_line(s, "file ends inside a facet (truncated?)");
    if (facets == 0) {
        lanes_error_set(s->err, "%s: no facets", s->path);
        return false;
    }
    return true;
}

static bool check_stl(stream *s, long long size)
{
    unsigned char head[84];
    size_t got = 0;
    while (got < sizeof head && fill(s)) {
        size_t k = s->len - s->pos < sizeof head - got ? s->len - s->pos : sizeof head - got;
        memcpy(head + got, s->buf + s->pos, k);
        got += k;
        s->pos += k;
    }
    /* The same rule Assimp uses: a file whose size matches its triangle
     * count is binary even when its 80-byte header starts with "solid". */
    if (got == sizeof head) {
        unsigned long count = (unsigned long)head[80] | (unsigned long)head[81] << 8 |
                              (unsigned long)head[82] << 16 | (unsigned long)head[83] << 24;
        /* Assimp's format detection compares in 32 bits, where a huge
         * count wraps around to the file size and the file is taken for
         * binary; refuse such a count here rather than rely on the
         * importer's later size check. */
        if ((uint32_t)(84u + 50u * (uint32_t)count) == (uint32_t)size &&
            (unsigned long long)size != 84ull + 50ull * count) {
            lanes_error_set(s->err,
                            "%s: binary STL declares %lu triangles, far more than its "
                            "%lld bytes hold",
                            s->path, count, size);
            return false;
        }
        if ((unsigned long long)size == 84ull + 50ull * count) {
            if (count == 0) {
                lanes_error_set(s->err, "%s: binary STL with no triangles", s->path);
                return false;
            }
            return check_stl_binary(s, count);
        }
    }
    size_t i = 0;
    while (i < got && isspace(head[i]))
        i++;
    if (got - i >= 5 && memcmp(head + i, "solid", 5) == 0) {
        rewind(s->f);
        s->pos = s->len = 0;
        s->base = 0;
        s->eof = false;
        return check_stl_ascii(s);
    }
    if (got < sizeof head) {
        lanes_error_set(s->err,
                        "%s: %lld bytes: too short for a binary STL, and not ASCII "
                        "(no 'solid')",
                        s->path, size);
        return false;
    }
    unsigned long count = (unsigned long)head[80] | (unsigned long)head[81] << 8 |
                          (unsigned long)head[82] << 16 | (unsigned long)head[83] << 24;
    lanes_error_set(s->err,
                    "%s: binary STL declares %lu triangles (%llu bytes) but the file "
                    "has %lld bytes (truncated?)",
                    s->path, count, 84ull + 50ull * count, size);
    return false;
}

/* ---- format detection and the pre-check ---- */

typedef enum { FMT_OTHER, FMT_OBJ, FMT_OFF, FMT_PLY, FMT_STL } mesh_format;

static bool ext_is(const char *path, const char *ext)
{
    const char *dot = strrchr(path, '.');
    const char *slash = strrchr(path, '/');
    if (!dot || (slash && dot < slash))
        return false;
    dot++;
    size_t n = strlen(ext);
    if (strlen(dot) != n)
        return false;
    for (size_t i = 0; i < n; i++)
        if (tolower((unsigned char)dot[i]) != ext[i])
            return false;
    return true;
}

/* By extension, as Assimp chooses its importer; for other extensions by
 * content, because Assimp then also tries importers by signature. */
static mesh_format detect(const char *path, const unsigned char *head, size_t n)
{
    if (ext_is(path, "obj"))
        return FMT_OBJ;
    if (ext_is(path, "off"))
        return FMT_OFF;
    if (ext_is(path, "ply"))
        return FMT_PLY;
    if (ext_is(path, "stl"))
        return FMT_STL;
    if (n >= 4 && memcmp(head, "ply", 3) == 0 && (head[3] == '\n' || head[3] == '\r'))
        return FMT_PLY;
    size_t i = 0;
    while (i < n && isspace(head[i]))
        i++;
    if (n - i >= 5 && memcmp(head + i, "solid", 5) == 0)
        return FMT_STL;
    size_t j = i;
    while (j < n && !isspace(head[j]))
        j++;
    tok t = {(const char *)head + i, j - i};
    if (is_off_keyword(t))
        return FMT_OFF;
    return FMT_OTHER;
}

/* Opens the file with the checks every format shares: exists, is a
 * regular file, is not empty. */
static FILE *open_mesh(const char *path, long long *size, lanes_error *err)
{
    struct stat st;
    if (stat(path, &st) != 0) {
        if (errno == ENOENT)
            lanes_error_set(err, "%s: no such file", path);
        else
            lanes_error_set(err, "%s: %s", path, strerror(errno));
        return NULL;
    }
    if (S_ISDIR(st.st_mode)) {
        lanes_error_set(err, "%s: is a directory, not a mesh file", path);
        return NULL;
    }
    /* A FIFO would block fopen until a writer comes (forever, for a
     * stray mkfifo), and Assimp reads devices by their stat size; a mesh
     * is a file. */
    if (!S_ISREG(st.st_mode)) {
        lanes_error_set(err, "%s: not a regular file (a device, FIFO or socket)", path);
        return NULL;
    }
    if (st.st_size == 0) {
        lanes_error_set(err, "%s: empty file", path);
        return NULL;
    }
    FILE *f = fopen(path, "rb");
    if (!f) {
        lanes_error_set(err, "%s: cannot open: %s", path, strerror(errno));
        return NULL;
    }
    *size = (long long)st.st_size;
    return f;
}

bool lanes_mesh_precheck(const char *path, lanes_error *err)
{
    long long size = 0;
    FILE *f = open_mesh(path, &size, err);
    if (!f)
        return false;
    stream *s = calloc(1, sizeof *s);
    if (!s) {
        fclose(f);
        lanes_error_set(err, "%s: out of memory", path);
        return false;
    }
    s->f = f;
    s->path = path;
    s->err = err;
    fill(s);
    mesh_format fmt = detect(path, s->buf, s->len);
    bool ok = true;
    switch (fmt) {
    case FMT_OBJ: ok = check_obj(s); break;
    case FMT_OFF: ok = check_off(s); break;
    case FMT_PLY: ok = check_ply(s); break;
    case FMT_STL: ok = check_stl(s, size); break;
    case FMT_OTHER: break;
    }
    free(s->ln);
    free(s);
    fclose(f);
    return ok;
}

/* ---- glTF: what Assimp should have returned ---- */

#define MAX_GLTF_JSON (64u << 20)

/* A glTF integer as Assimp's reader takes it: 2.5 or 1e0 are not one
 * (rapidjson keeps them as doubles, and Assimp then ignores the member,
 * where cJSON's valueint would silently truncate). -1: not an integer in
 * [0, max]. */
static long long gltf_int(const cJSON *v, double max)
{
    if (!cJSON_IsNumber(v) || !(v->valuedouble >= 0 && v->valuedouble <= max) ||
        v->valuedouble != floor(v->valuedouble))
        return -1;
    return (long long)v->valuedouble;
}

static long long accessor_count(const cJSON *accessors, const cJSON *index)
{
    long long i = gltf_int(index, INT_MAX);
    const cJSON *a = i >= 0 ? cJSON_GetArrayItem(accessors, (int)i) : NULL;
    return a ? gltf_int(cJSON_GetObjectItemCaseSensitive(a, "count"), 1e15) : -1;
}

/* Data URIs that Assimp 5.2 misreads: it leaks its buffers when the data
 * holds a character outside base64, and it keeps the offsets of the
 * parts of a URI in a signed char, so a media type of more than about 120
 * characters makes it read before the string (found by fuzz_mesh_gltf).
 * Both are refused here, for buffers and images alike. */
static bool check_data_uris(const char *path, const cJSON *root, const char *array,
                            lanes_error *err)
{
    const cJSON *it;
    int i = 0;
    cJSON_ArrayForEach(it, cJSON_GetObjectItemCaseSensitive(root, array))
    {
        const cJSON *uri = cJSON_GetObjectItemCaseSensitive(it, "uri");
        const char *u = cJSON_IsString(uri) ? uri->valuestring : NULL;
        if (u && strncmp(u, "data:", 5) == 0) {
            const char *comma = strchr(u, ',');
            if (!comma || comma - u > 100) {
                lanes_error_set(err, "%s: %s[%d].uri: malformed data URI (%s)", path, array, i,
                                comma ? "header longer than 100 characters" : "no ','");
                return false;
            }
            bool b64 = false;
            for (const char *p = u; p < comma; p++)
                b64 = b64 || (*p == ';' && strncmp(p + 1, "base64", 6) == 0);
            for (const char *q = comma + 1; b64 && *q; q++) {
                if (!isalnum((unsigned char)*q) && *q != '+' && *q != '/' && *q != '=') {
                    lanes_error_set(err, "%s: %s[%d].uri: invalid base64 data", path, array, i);
                    return false;
                }
            }
        }
        i++;
    }
    return true;
}

static void le32(const unsigned char *b, uint32_t *w, int n)
{
    for (int i = 0; i < n; i++)
        w[i] = (uint32_t)b[4 * i] | (uint32_t)b[4 * i + 1] << 8 | (uint32_t)b[4 * i + 2] << 16 |
               (uint32_t)b[4 * i + 3] << 24;
}

/* The sizes in a GLB 2 header (w: magic, version, total length, first
 * chunk length, its type) and of the binary chunk after it. Assimp 5.2
 * allocates each before reading a byte (a 600-byte file claiming a 1.5 GB
 * JSON chunk made it allocate that, found by fuzz_mesh_glb), so each must
 * fit in the file. 1: fine; 0: cannot tell (Assimp decides); -1: error
 * (message set). */
static int glb_sizes(const char *path, FILE *f, const uint32_t w[5], lanes_error *err)
{
    if (fseek(f, 0, SEEK_END) != 0)
        return 0;
    long size = ftell(f);
    if (size < 20)
        return 0;
    unsigned long long n = (unsigned long long)size;
    if (w[2] > n || w[3] > n - 20) {
        lanes_error_set(err,
                        "%s: the GLB header declares %lu bytes and a first chunk of %lu, but "
                        "the file has %llu bytes (truncated?)",
                        path, (unsigned long)w[2], (unsigned long)w[3], n);
        return -1;
    }
    /* Version 2: the binary chunk that may follow, padded to 4 bytes. */
    unsigned long long at = 20ull + ((w[3] + 3ull) & ~3ull);
    unsigned char h[8];
    uint32_t c[2];
    if (at + 8 <= w[2] && fseek(f, (long)at, SEEK_SET) == 0 &&
        fread(h, 1, sizeof h, f) == sizeof h) {
        le32(h, c, 2);
        if (c[0] > n - at - 8) {
            lanes_error_set(err,
                            "%s: byte %llu: GLB chunk of %lu bytes, but the file ends %llu "
                            "bytes later (truncated?)",
                            path, at, (unsigned long)c[0], n - at - 8);
            return -1;
        }
    }
    return 1;
}

/* Triangles the file's primitives describe. Assimp's glTF importer drops a
 * face whose index is out of range and goes on, so a count below this one
 * means the file is broken. 1: *expected set; 0: no check possible (the
 * importer will judge); -1: error (message set). */
static int gltf_expected(const char *path, unsigned long long *expected, lanes_error *err)
{
    bool glb = ext_is(path, "glb"), gltf = ext_is(path, "gltf");
    if (!glb && !gltf)
        return 0;
    FILE *f = fopen(path, "rb");
    if (!f)
        return 0;
    char *text = NULL;
    size_t len = 0;
    int result = 0;
    if (glb) {
        unsigned char h[20];
        uint32_t w[5];
        if (fread(h, 1, sizeof h, f) != sizeof h) {
            lanes_error_set(err, "%s: not a GLB file (shorter than its 20-byte header)", path);
            result = -1;
            goto done;
        }
        le32(h, w, 5);
        /* Assimp would try every other importer on a .glb without the
         * magic (see known_extension). */
        if (w[0] != 0x46546C67u || w[1] != 2) {
            lanes_error_set(err, "%s: not a GLB 2 file (%s)", path,
                            w[0] != 0x46546C67u ? "no 'glTF' magic" : "another version");
            result = -1;
            goto done;
        }
        int sz = glb_sizes(path, f, w, err);
        if (sz <= 0) {
            result = sz;
            goto done;
        }
        if (w[4] != 0x4E4F534Au || w[3] > MAX_GLTF_JSON) {
            lanes_error_set(err, "%s: the first GLB chunk is %s", path,
                            w[4] != 0x4E4F534Au ? "not JSON" : "JSON of more than 64 MiB");
            result = -1;
            goto done;
        }
        if (fseek(f, (long)sizeof h, SEEK_SET) != 0)
            goto done;
        len = w[3];
    } else {
        if (fseek(f, 0, SEEK_END) != 0)
            goto done;
        long n = ftell(f);
        if (n < 0 || (unsigned long)n > MAX_GLTF_JSON || fseek(f, 0, SEEK_SET) != 0)
            goto done;
        len = (size_t)n;
    }
    text = malloc(len + 1);
    if (!text || fread(text, 1, len, f) != len)
        goto done;
    const char *end = NULL;
    cJSON *root = cJSON_ParseWithLengthOpts(text, len, &end, false);
    if (!root) {
        if (gltf) {
            size_t off = end && end >= text && end <= text + len ? (size_t)(end - text) : len;
            unsigned long line = 1;
            for (size_t i = 0; i < off; i++)
                line += text[i] == '\n';
            lanes_error_set(err, "%s: line %lu: JSON syntax error%s", path, line,
                            off >= len ? " (unexpected end of file: truncated?)" : "");
        } else {
            lanes_error_set(err, "%s: the JSON chunk is not valid JSON", path);
        }
        result = -1;
        goto done;
    }
    /* Both glTF importers require asset.version; a file they both refuse
     * goes to every other importer (see known_extension). */
    const cJSON *asset = cJSON_GetObjectItemCaseSensitive(root, "asset");
    const cJSON *version = cJSON_GetObjectItemCaseSensitive(asset, "version");
    const char *v = cJSON_IsString(version) ? version->valuestring : "";
    if (v[0] != '2' && (glb || strcmp(v, "1.0") != 0)) {
        lanes_error_set(err, "%s: not a glTF file: asset.version must be \"2.0\"%s", path,
                        glb ? "" : " (or \"1.0\")");
        cJSON_Delete(root);
        result = -1;
        goto done;
    }
    if (!check_data_uris(path, root, "buffers", err) || !check_data_uris(path, root, "images", err)) {
        cJSON_Delete(root);
        result = -1;
        goto done;
    }
    const cJSON *meshes = cJSON_GetObjectItemCaseSensitive(root, "meshes");
    const cJSON *accessors = cJSON_GetObjectItemCaseSensitive(root, "accessors");
    unsigned long long tris = 0;
    result = 1;
    const cJSON *m;
    int mi = 0;
    cJSON_ArrayForEach(m, meshes)
    {
        const cJSON *p, *prims = cJSON_GetObjectItemCaseSensitive(m, "primitives");
        int pi = -1;
        cJSON_ArrayForEach(p, prims)
        {
            pi++;
            const cJSON *mode = cJSON_GetObjectItemCaseSensitive(p, "mode");
            const cJSON *attrs = cJSON_GetObjectItemCaseSensitive(p, "attributes");
            const cJSON *idx = cJSON_GetObjectItemCaseSensitive(p, "indices");
            long long md = mode ? gltf_int(mode, 6) : 4;
            const cJSON *pos = cJSON_GetObjectItemCaseSensitive(attrs, "POSITION");
            long long n = accessor_count(accessors, idx ? idx : pos);
            /* Assimp 5.2 sizes a strip's or fan's faces as count - 2 (a
             * line strip's as count - 1) in unsigned arithmetic, and a
             * primitive whose positions it cannot find (none, or an index
             * of 0.7) has count 0: it then allocates 64 GiB (found by
             * fuzz_mesh_gltf). Such primitives draw nothing, so they are
             * refused rather than passed on. */
            bool strip = md == 3 || md == 5 || md == 6;
            long long need = md == 3 ? 2 : strip ? 3 : 1;
            const char *bad = NULL;
            if (md < 0)
                bad = "mode is not an integer from 0 to 6";
            else if (!pos)
                bad = "no POSITION attribute";
            else if (strip && n < 0)
                bad = "a strip or fan without a valid accessor index and count";
            else if (n >= 0 && n < need)
                bad = "too few vertices for its mode";
            if (bad) {
                lanes_error_set(err, "%s: meshes[%d].primitives[%d]: %s", path, mi, pi, bad);
                result = -1;
                cJSON_Delete(root);
                goto done;
            }
            if (md < 4 || md > 6)
                continue; /* points and lines */
            if (!pos || n < 0) {
                result = 0;
                continue;
            }
            tris += (unsigned long long)(md == 4 ? n / 3 : n > 2 ? n - 2 : 0);
        }
        mi++;
    }
    *expected = tris;
    cJSON_Delete(root);
done:
    free(text);
    fclose(f);
    return result;
}

/* ---- Assimp ---- */

/* Every file Assimp opens goes through these callbacks: the mesh, and the
 * files it names (an OBJ's mtllib, a glTF's buffers and images). Only
 * regular files open. Assimp's own file system opens whatever fopen opens,
 * directories included: "mtllib /" made it open the OBJ's directory, fail
 * to read it and leak the stream (found by fuzz_mesh_obj), and a FIFO would
 * block it. Read-only: Assimp never needs to write here. */
static FILE *io_file(struct aiFile *a)
{
    return (FILE *)(void *)a->UserData;
}

static size_t io_read(struct aiFile *a, char *buf, size_t size, size_t count)
{
    return size && count ? fread(buf, size, count, io_file(a)) : 0;
}

static size_t io_write(struct aiFile *a, const char *buf, size_t size, size_t count)
{
    (void)a;
    (void)buf;
    (void)size;
    (void)count;
    return 0;
}

static size_t io_tell(struct aiFile *a)
{
    long p = ftell(io_file(a));
    return p < 0 ? 0 : (size_t)p;
}

static size_t io_size(struct aiFile *a)
{
    struct stat st;
    return fstat(fileno(io_file(a)), &st) == 0 ? (size_t)st.st_size : 0;
}

static enum aiReturn io_seek(struct aiFile *a, size_t offset, enum aiOrigin origin)
{
    int whence = origin == aiOrigin_SET ? SEEK_SET : origin == aiOrigin_CUR ? SEEK_CUR : SEEK_END;
    return fseek(io_file(a), (long)offset, whence) == 0 ? aiReturn_SUCCESS : aiReturn_FAILURE;
}

static void io_flush(struct aiFile *a)
{
    (void)a;
}

static struct aiFile *io_open(struct aiFileIO *io, const char *path, const char *mode)
{
    (void)io;
    struct stat st;
    if (strpbrk(mode, "wa+") || stat(path, &st) != 0 || !S_ISREG(st.st_mode))
        return NULL;
    struct aiFile *a = calloc(1, sizeof *a);
    FILE *f = a ? fopen(path, "rb") : NULL;
    if (!f) {
        free(a);
        return NULL;
    }
    a->ReadProc = io_read;
    a->WriteProc = io_write;
    a->TellProc = io_tell;
    a->FileSizeProc = io_size;
    a->SeekProc = io_seek;
    a->FlushProc = io_flush;
    a->UserData = (aiUserData)(void *)f;
    return a;
}

static void io_close(struct aiFileIO *io, struct aiFile *a)
{
    (void)io;
    if (a) {
        fclose(io_file(a));
        free(a);
    }
}

/* Assimp's own messages rarely name the file; some do, most do not. */
static void assimp_error(const char *path, const char *what, lanes_error *err)
{
    const char *msg = aiGetErrorString();
    if (!msg || !*msg)
        msg = "unknown error";
    lanes_error_set(err, "%s: %s: %s", path, what, msg);
}

static const char *mesh_name(const struct aiMesh *m)
{
    return m->mName.length > 0 ? m->mName.data : "";
}

/* The raw import, before any post-processing runs on it: post-processing
 * steps assume a well-formed structure (Triangulate would follow a null
 * index array), so this is where a half-read file must be caught. */
static bool check_raw(const char *path, const struct aiScene *sc, lanes_error *err)
{
    if (sc->mNumMeshes > 0 && !sc->mMeshes) {
        lanes_error_set(err, "%s: Assimp returned no mesh array", path);
        return false;
    }
    for (unsigned m = 0; m < sc->mNumMeshes; m++) {
        const struct aiMesh *me = sc->mMeshes[m];
        if (!me || (me->mNumVertices > 0 && !me->mVertices) || (me->mNumFaces > 0 && !me->mFaces)) {
            lanes_error_set(err, "%s: mesh %u is incomplete (truncated file?)", path, m);
            return false;
        }
        for (unsigned v = 0; v < me->mNumVertices; v++) {
            const struct aiVector3D *p = &me->mVertices[v];
            if (!isfinite(p->x) || !isfinite(p->y) || !isfinite(p->z)) {
                lanes_error_set(err, "%s: mesh %u '%s': vertex %u is not finite", path, m,
                                mesh_name(me), v);
                return false;
            }
        }
        for (unsigned f = 0; f < me->mNumFaces; f++) {
            const struct aiFace *fa = &me->mFaces[f];
            if (fa->mNumIndices == 0 || !fa->mIndices) {
                lanes_error_set(err,
                                "%s: mesh %u '%s': face %u has no vertices (truncated "
                                "file?)",
                                path, m, mesh_name(me), f);
                return false;
            }
            for (unsigned k = 0; k < fa->mNumIndices; k++) {
                if (fa->mIndices[k] >= me->mNumVertices) {
                    lanes_error_set(err, "%s: mesh %u '%s': face %u refers to vertex %u of %u",
                                    path, m, mesh_name(me), f, fa->mIndices[k], me->mNumVertices);
                    return false;
                }
            }
        }
    }
    return true;
}

typedef struct collect {
    const char *path;
    const struct aiScene *sc;
    lanes_mesh *out;
    bool fill; /* false: count only */
    unsigned long long tris, verts;
    lanes_error *err;
} collect;

static void to_xform(const struct aiMatrix4x4 *a, lanes_xform *x)
{
    const double r[3][4] = {
        {a->a1, a->a2, a->a3, a->a4}, {a->b1, a->b2, a->b3, a->b4}, {a->c1, a->c2, a->c3, a->c4}};
    memcpy(x->m, r, sizeof r);
}

static bool walk(collect *c, const struct aiNode *node, const lanes_xform *parent, int depth)
{
    if (depth > MAX_NODE_DEPTH) {
        lanes_error_set(c->err, "%s: node hierarchy deeper than %d (a cycle?)", c->path,
                        MAX_NODE_DEPTH);
        return false;
    }
    lanes_xform local, x;
    to_xform(&node->mTransformation, &local);
    lanes_xform_mul(&x, parent, &local);
    for (unsigned i = 0; i < node->mNumMeshes; i++) {
        unsigned mi = node->mMeshes[i];
        if (mi >= c->sc->mNumMeshes) {
            lanes_error_set(c->err, "%s: node '%s' refers to mesh %u of %u", c->path,
                            node->mName.data, mi, c->sc->mNumMeshes);
            return false;
        }
        const struct aiMesh *me = c->sc->mMeshes[mi];
        unsigned long long ntri = 0;
        for (unsigned f = 0; f < me->mNumFaces; f++)
            ntri += me->mFaces[f].mNumIndices == 3;
        if (ntri == 0)
            continue;
        if (!c->fill) {
            c->tris += ntri;
            c->verts += me->mNumVertices;
            if (c->tris > LANES_SCENE_MAX_TRIANGLES || c->verts > MAX_VERTICES) {
                lanes_error_set(c->err, "%s: more than %zu triangles or %llu vertices", c->path,
                                LANES_SCENE_MAX_TRIANGLES, MAX_VERTICES);
                return false;
            }
            continue;
        }
        uint32_t base = (uint32_t)c->verts;
        for (unsigned v = 0; v < me->mNumVertices; v++) {
            const struct aiVector3D *p = &me->mVertices[v];
            float in[3] = {p->x, p->y, p->z};
            float *o = c->out->positions + 3 * (c->verts + v);
            lanes_xform_apply(&x, in, o);
            if (!isfinite(o[0]) || !isfinite(o[1]) || !isfinite(o[2])) {
                lanes_error_set(c->err,
                                "%s: mesh %u '%s': vertex %u is not finite after the "
                                "node transforms",
                                c->path, mi, mesh_name(me), v);
                return false;
            }
        }
        uint32_t *idx = c->out->indices + 3 * c->tris;
        for (unsigned f = 0; f < me->mNumFaces; f++) {
            const struct aiFace *fa = &me->mFaces[f];
            if (fa->mNumIndices != 3)
                continue; /* points and lines */
            for (int k = 0; k < 3; k++) {
                /* Checked again: post-processing rewrote the indices. */
                if (!fa->mIndices || fa->mIndices[k] >= me->mNumVertices) {
                    lanes_error_set(c->err,
                                    "%s: mesh %u: face %u has a bad index after "
                                    "triangulation",
                                    c->path, mi, f);
                    return false;
                }
                *idx++ = base + fa->mIndices[k];
            }
        }
        c->tris += ntri;
        c->verts += me->mNumVertices;
    }
    if (node->mNumChildren > 0 && !node->mChildren) {
        lanes_error_set(c->err, "%s: node '%s' has no child array", c->path, node->mName.data);
        return false;
    }
    for (unsigned i = 0; i < node->mNumChildren; i++) {
        if (!node->mChildren[i] || !walk(c, node->mChildren[i], &x, depth + 1))
            return false;
    }
    return true;
}

/* Joins vertices at exactly the same position, across meshes and node
 * instances too. Assimp's JoinIdenticalVertices also compares normals and
 * texture coordinates, so an STL (one normal per facet) would keep three
 * vertices per triangle and lose all connectivity. */
static bool weld(lanes_mesh *m)
{
    size_t n = m->vertex_count, size = 16;
    while (size < 2 * n)
        size *= 2;
    uint32_t *slot = calloc(size, sizeof *slot); /* vertex index + 1; 0 = empty */
    uint32_t *remap = malloc((n ? n : 1) * sizeof *remap);
    if (!slot || !remap) {
        free(slot);
        free(remap);
        return false;
    }
    size_t kept = 0;
    float *p = m->positions;
    for (size_t v = 0; v < n; v++) {
        float q[3];
        uint32_t bits[3];
        for (int a = 0; a < 3; a++)
            q[a] = p[3 * v + a] + 0.0f; /* -0 and +0 are one position */
        memcpy(bits, q, sizeof bits);
        uint64_t h = (bits[0] * 0x9e3779b97f4a7c15ull) ^ (bits[1] * 0xc2b2ae3d27d4eb4full) ^
                     (bits[2] * 0x165667b19e3779f9ull);
        size_t i = (size_t)(h ^ (h >> 29)) & (size - 1);
        for (;;) {
            if (slot[i] == 0) {
                slot[i] = (uint32_t)kept + 1;
                memcpy(p + 3 * kept, q, sizeof q);
                remap[v] = (uint32_t)kept++;
                break;
            }
            const float *o = p + 3 * (slot[i] - 1);
            if (o[0] == q[0] && o[1] == q[1] && o[2] == q[2]) {
                remap[v] = slot[i] - 1;
                break;
            }
            i = (i + 1) & (size - 1);
        }
    }
    for (size_t k = 0; k < 3 * m->triangle_count; k++)
        m->indices[k] = remap[m->indices[k]];
    m->vertex_count = kept;
    free(slot);
    free(remap);
    return true;
}

/* For an extension no importer claims, Assimp tries every importer on the
 * content, so glTF text in a .dat file reached the glTF importer without
 * the glTF checks here (and leaked, found by fuzzing unknown extensions);
 * the same goes for OBJ text, which Assimp recognizes by a "v " at the
 * start of any line. Only extensions Assimp knows are passed on. */
static bool known_extension(const char *path, lanes_error *err)
{
    const char *slash = strrchr(path, '/');
    const char *base = slash ? slash + 1 : path;
    const char *dot = strrchr(base, '.');
    char ext[40];
    if (dot && dot != base && dot[1] && strlen(dot) < sizeof ext) {
        snprintf(ext, sizeof ext, "%s", dot);
        if (aiIsExtensionSupported(ext))
            return true;
    }
    lanes_error_set(err,
                    "%s: cannot import: %s (mesh files need the extension of their format: "
                    ".obj, .ply, .off, .stl, .gltf, .glb, or another Assimp reads)",
                    path, dot && dot != base && dot[1] ? "unknown file extension" : "no file extension");
    return false;
}

bool lanes_mesh_read(const char *path, lanes_mesh *out, lanes_error *err)
{
    memset(out, 0, sizeof *out);
    if (!lanes_mesh_precheck(path, err) || !known_extension(path, err))
        return false;
    unsigned long long expected = 0;
    int gl = gltf_expected(path, &expected, err);
    if (gl < 0)
        return false;

    struct aiPropertyStore *props = aiCreatePropertyStore();
    if (!props) {
        lanes_error_set(err, "%s: out of memory", path);
        return false;
    }
    /* Skeleton-only meshes are bone visualizations, not geometry. */
    aiSetImportPropertyInteger(props, AI_CONFIG_IMPORT_NO_SKELETON_MESHES, 1);
    struct aiFileIO io = {io_open, io_close, NULL};
    const struct aiScene *sc = aiImportFileExWithProperties(path, 0, &io, props);
    aiReleasePropertyStore(props);
    if (!sc) {
        assimp_error(path, "cannot import", err);
        return false;
    }
    bool ok = false;
    if (!check_raw(path, sc, err))
        goto done;
    unsigned long long got = 0;
    for (unsigned m = 0; m < sc->mNumMeshes; m++)
        for (unsigned f = 0; f < sc->mMeshes[m]->mNumFaces; f++)
            got += sc->mMeshes[m]->mFaces[f].mNumIndices == 3;
    if (gl > 0 && got < expected) {
        lanes_error_set(err,
                        "%s: the primitives describe %llu triangles but Assimp kept %llu "
                        "(out-of-range vertex indices?)",
                        path, expected, got);
        goto done;
    }
    /* ValidateDataStructure is left out on purpose: check_raw covers what
     * we rely on, and the validator rejects files that are fine for us
     * (an OBJ "f 1 2" makes it fail on its own primitive-type flags). */
    sc = aiApplyPostProcessing(sc, aiProcess_Triangulate);
    if (!sc) {
        assimp_error(path, "post-processing failed", err);
        return false;
    }
    if (!sc->mRootNode) {
        lanes_error_set(err, "%s: the file has no node hierarchy", path);
        goto done;
    }
    collect c = {path, sc, out, false, 0, 0, err};
    lanes_xform id;
    lanes_xform_identity(&id);
    if (!walk(&c, sc->mRootNode, &id, 0))
        goto done;
    if (c.tris == 0) {
        lanes_error_set(err, "%s: no triangles (only points, lines or empty meshes)", path);
        goto done;
    }
    out->positions = malloc((size_t)c.verts * 3 * sizeof(float));
    out->indices = malloc((size_t)c.tris * 3 * sizeof(uint32_t));
    if (!out->positions || !out->indices) {
        lanes_error_set(err, "%s: out of memory for %llu triangles", path, c.tris);
        goto done;
    }
    out->vertex_count = (size_t)c.verts;
    out->triangle_count = (size_t)c.tris;
    c.fill = true;
    c.tris = c.verts = 0;
    if (!walk(&c, sc->mRootNode, &id, 0))
        goto done;
    if (!weld(out)) {
        lanes_error_set(err, "%s: out of memory joining vertices", path);
        goto done;
    }
    ok = true;
done:
    aiReleaseImport(sc);
    if (!ok)
        lanes_mesh_free(out);
    return ok;
}

bool lanes_mesh_import(lanes_scene *scene, const char *path, const lanes_xform *xf,
                       uint32_t material, lanes_error *err)
{
    lanes_mesh m;
    if (!lanes_mesh_read(path, &m, err))
        return false;
    bool ok = lanes_scene_add_mesh(scene, &m, xf, material, path, err);
    lanes_mesh_free(&m);
    return ok;
}
