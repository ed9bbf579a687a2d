/* The first stage of mesh import (mesh_import.h): streaming checkers of
 * our own for OBJ, OFF, PLY and STL files and a check of glTF's declared
 * triangle counts, run before Assimp sees a file. Internal to build/: the
 * buffered reader and the token and number parsers the checkers share
 * (mesh_stream.c), one checker per format (mesh_check_<format>.c), and
 * the dispatch by format (mesh_precheck.c).
 *
 * Compiled for the x86-64 baseline. */
#ifndef LANES_BUILD_MESH_CHECK_H
#define LANES_BUILD_MESH_CHECK_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "build/error.h"
#include "build/scene.h" /* LANES_SCENE_MAX_TRIANGLES */

/* Bounds on what a sane mesh file holds; past them a count is a corrupt
 * header, not a mesh, and we refuse before anything is allocated. */
#define MAX_VERTICES ((unsigned long long)UINT32_MAX)
#define MAX_POLYGON 65536    /* vertices of one face */
#define MAX_OFF_POLYGON 9    /* what Assimp 5.2's OFF reader keeps */
#define MAX_LINE (64u << 20) /* bytes of one text line */

#if defined(__GNUC__)
#define PRINTF_LIKE(f, a) __attribute__((format(printf, f, a)))
#else
#define PRINTF_LIKE(f, a)
#endif

/* ---- a buffered reader that knows its line number and byte offset ---- */

typedef struct mesh_stream {
    FILE *f;
    const char *path;
    lanes_error *err;
    unsigned char buf[1 << 16];
    size_t pos, len;
    unsigned long long base; /* file offset of buf[0] */
    bool eof, ioerr;
    unsigned long line; /* number of the line last returned */
    /* what the file declares or holds, for the import's memory bound
     * (mesh_import_fits): set by each checker once it knows */
    unsigned long long vertices, faces;
    char *ln;           /* that line, NUL-terminated, without \r\n */
    size_t ln_len, ln_cap;
} mesh_stream;

/* Refills the buffer when it is used up; false at end of file (s->ioerr
 * tells a read error from the end). */
bool mesh_fill(mesh_stream *s);
/* The file offset of the next unread byte. */
unsigned long long mesh_offset(const mesh_stream *s);
/* "file: line N: what" for the text formats; "file: byte N: what" for
 * binary data, which has no lines. Both record LANES_ERR_BAD_INPUT in
 * s->err and return false, for `return mesh_fail_line(...)`. */
bool mesh_fail_line(mesh_stream *s, const char *fmt, ...) PRINTF_LIKE(2, 3);
bool mesh_fail_byte(mesh_stream *s, unsigned long long at, const char *fmt, ...) PRINTF_LIKE(3, 4);
/* 1: a line is in s->ln; 0: end of file; -1: error (message set). */
int mesh_get_line(mesh_stream *s);
/* Whether importing s->vertices and s->faces fits in the memory this
 * process may use (lanes_memory_fits); false with the message set. Called
 * once a checker has read the whole file, so that the counts are the ones
 * the file holds (a header that claims more is reported as truncated). */
bool mesh_import_fits(mesh_stream *s);
/* n bytes of binary data; false (message set) when the file ends first. */
bool mesh_get_bytes(mesh_stream *s, void *dst, size_t n);

/* ---- tokens and numbers ---- */

typedef struct mesh_tok {
    const char *p;
    size_t n;
} mesh_tok;

static inline bool is_space(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

static inline bool next_tok(const char **cur, mesh_tok *t)
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

static inline bool tok_is(mesh_tok t, const char *w)
{
    return t.n == strlen(w) && memcmp(t.p, w, t.n) == 0;
}

/* tok_is ignoring ASCII case, for formats whose keywords are written in
 * either (ASCII STL: "SOLID", "FACET NORMAL" from some CAD exporters). */
static inline bool tok_is_nocase(mesh_tok t, const char *w)
{
    if (t.n != strlen(w)) return false;
    for (size_t i = 0; i < t.n; i++) {
        unsigned char c = (unsigned char)t.p[i];
        if ((c >= 'A' && c <= 'Z' ? c + ('a' - 'A') : c) != (unsigned char)w[i]) return false;
    }
    return true;
}

/* Whether head[0 .. n) starts with "solid" in any case, after white
 * space: an ASCII STL (unless its size says binary). */
static inline bool mesh_starts_solid(const unsigned char *head, size_t n)
{
    size_t i = 0;
    while (i < n && (head[i] == ' ' || (head[i] >= '\t' && head[i] <= '\r'))) i++;
    mesh_tok t = {(const char *)head + i, n - i < 5 ? n - i : 5};
    return tok_is_nocase(t, "solid");
}

/* The triangle count a binary STL's 84-byte header declares (bytes 80-83,
 * little-endian). */
static inline unsigned long mesh_stl_declared_count(const unsigned char head[84])
{
    return (unsigned long)head[80] | (unsigned long)head[81] << 8 | (unsigned long)head[82] << 16 |
           (unsigned long)head[83] << 24;
}

/* Printable form of a token for messages, cut short. */
const char *mesh_tok_str(mesh_tok t, char out[48]);

enum { NUM_OK, NUM_BAD, NUM_NONFINITE };

/* Numbers as Assimp's readers take them (see mesh_stream.c): NUM_OK,
 * NUM_BAD or NUM_NONFINITE. */
int mesh_parse_real(mesh_tok t, double *out);
int mesh_parse_int(mesh_tok t, long long *out);
int mesh_parse_uint(mesh_tok t, long long *out);
int mesh_parse_real_stream(mesh_tok t, double *out);
/* Three finite coordinates from *cur, or false with the line's message. */
bool mesh_read_xyz(mesh_stream *s, const char **cur, const char *what);

/* ---- the checkers: true when the file is one Assimp reads as we do ---- */

bool mesh_check_obj(mesh_stream *s);
bool mesh_check_off(mesh_stream *s);
bool mesh_check_ply(mesh_stream *s);
bool mesh_check_stl(mesh_stream *s, long long size);
/* An OFF file's first keyword (OFF, COFF, NOFF, ...), for detection. */
bool mesh_is_off_keyword(mesh_tok t);
/* The path's extension is ext (lower case), in any case. */
bool mesh_ext_is(const char *path, const char *ext);
/* For glTF/GLB files: the triangle count the primitives declare, in
 * *expected. 1: counted; 0: not a glTF file; -1: refused (message set). */
int mesh_gltf_expected(const char *path, unsigned long long *expected, lanes_error *err);

#endif
