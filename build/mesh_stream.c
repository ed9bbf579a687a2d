/* The reader and the token and number parsers the mesh checkers share
 * (mesh_check.h).
 *
 * Compiled for the x86-64 baseline. */

#include "build/mesh_check.h"

#include <ctype.h>
#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>


bool mesh_fill(mesh_stream *s)
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

unsigned long long mesh_offset(const mesh_stream *s)
{
    return s->base + s->pos;
}



/* "file: line N: what" for the text formats. */
bool mesh_fail_line(mesh_stream *s, const char *fmt, ...)
{
    char what[400];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    lanes_error_set(s->err, LANES_ERR_BAD_INPUT, "%s: line %lu: %s", s->path, s->line, what);
    return false;
}

/* "file: byte N: what" for binary data, which has no lines. */
bool mesh_fail_byte(mesh_stream *s, unsigned long long at, const char *fmt, ...)
{
    char what[400];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    lanes_error_set(s->err, LANES_ERR_BAD_INPUT, "%s: byte %llu: %s", s->path, at, what);
    return false;
}

/* 1: a line is in s->ln; 0: end of file; -1: error (message set). */
int mesh_get_line(mesh_stream *s)
{
    s->ln_len = 0;
    bool any = false;
    while (mesh_fill(s)) {
        any = true;
        const unsigned char *start = s->buf + s->pos;
        size_t avail = s->len - s->pos;
        const unsigned char *nl = memchr(start, '\n', avail);
        size_t take = nl ? (size_t)(nl - start) : avail;
        if (s->ln_len + take + 1 > s->ln_cap) {
            if (s->ln_len + take + 1 > MAX_LINE) {
                s->line++;
                mesh_fail_line(s, "line longer than %u bytes", MAX_LINE);
                return -1;
            }
            size_t cap = s->ln_cap ? s->ln_cap : 256;
            while (cap < s->ln_len + take + 1)
                cap *= 2;
            char *p = realloc(s->ln, cap);
            if (!p) {
                lanes_error_set(s->err, LANES_ERR_OUT_OF_MEMORY, "%s: out of memory reading a line", s->path);
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
        lanes_error_set(s->err, LANES_ERR_BAD_INPUT, "%s: read error: %s", s->path, strerror(errno));
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
                mesh_fail_line(s, "carriage return at column %zu (old Mac line endings are not "
                                  "supported)",
                               i + 1);
            else
                mesh_fail_line(s, "control character 0x%02x at column %zu (binary data in a text "
                                  "file?)",
                               c, i + 1);
            return -1;
        }
    }
    return 1;
}

bool mesh_get_bytes(mesh_stream *s, void *dst, size_t n)
{
    unsigned char *d = dst;
    while (n > 0) {
        if (!mesh_fill(s))
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



/* Printable form of a token for messages, cut short. */
const char *mesh_tok_str(mesh_tok t, char out[48])
{
    size_t n = t.n < 40 ? t.n : 40;
    for (size_t i = 0; i < n; i++)
        out[i] = isprint((unsigned char)t.p[i]) ? t.p[i] : '?';
    strcpy(out + n, t.n > n ? "..." : "");
    return out;
}

/* Decimal reals only. strtod would also take hex floats and "nan(...)",
 * which Assimp's own number reader does not, so the two would disagree
 * about what the file holds. Also non-finite as a float counts as
 * non-finite: the scene stores floats. (strtod follows the C locale; the
 * library never calls setlocale.) */
int mesh_parse_real(mesh_tok t, double *out)
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
int mesh_parse_int(mesh_tok t, long long *out)
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
int mesh_parse_uint(mesh_tok t, long long *out)
{
    if (t.n == 0 || t.p[0] == '+' || t.p[0] == '-')
        return NUM_BAD;
    return mesh_parse_int(t, out);
}

/* A real in the shape Assimp's fast_atoreal_move reads whole, for the
 * formats it parses as one stream (OFF, PLY, STL) rather than word by word
 * (OBJ): a point must be followed by a digit ("4." leaves the point for
 * the next number, which then fails: Assimp 5.2 throws and leaks the PLY
 * mesh, found by fuzz_mesh_ply), and at most 18 digits before the point
 * or in the exponent (more overflow its 64-bit reader, which then stops
 * without moving on). */
int mesh_parse_real_stream(mesh_tok t, double *out)
{
    size_t i = 0, n = t.n, digits = 0;
    if (i < n && (t.p[i] == '+' || t.p[i] == '-'))
        i++;
    if (i < n && !(t.p[i] >= '0' && t.p[i] <= '9') && t.p[i] != '.')
        return mesh_parse_real(t, out); /* nan, inf or a bad token */
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
    return i == n ? mesh_parse_real(t, out) : NUM_BAD;
}

/* Reads three coordinates of a vertex from *cur. */
bool mesh_read_xyz(mesh_stream *s, const char **cur, const char *what)
{
    for (int k = 0; k < 3; k++) {
        mesh_tok t;
        char b[48];
        double v;
        if (!next_tok(cur, &t))
            return mesh_fail_line(s, "%s has fewer than 3 coordinates", what);
        int r = mesh_parse_real_stream(t, &v);
        if (r == NUM_BAD)
            return mesh_fail_line(s, "bad number '%s' in a vertex", mesh_tok_str(t, b));
        if (r == NUM_NONFINITE)
            return mesh_fail_line(s, "vertex coordinate '%s' is not a finite float", mesh_tok_str(t, b));
    }
    return true;
}
