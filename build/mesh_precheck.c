/* Format detection and the pre-check by format (lanes_mesh_precheck,
 * mesh_import.h; the checkers are in mesh_check_<format>.c).
 *
 * Compiled for the x86-64 baseline. */
#define _POSIX_C_SOURCE 200809L /* stat, for "is a directory" before Assimp sees it */

#include "build/mesh_import.h"
#include "build/mesh_check.h"
#include "build/memory_limit.h"

#include <ctype.h>
#include <errno.h>
#include <stdlib.h>
#include <sys/stat.h>

typedef enum { FMT_OTHER, FMT_OBJ, FMT_OFF, FMT_PLY, FMT_STL } mesh_format;

/* What Assimp 5.2 holds per vertex and per face while it imports, before
 * lanes copies the triangles out: measured on binary PLY, 10M vertices and
 * one face peaked at 404 MB (38 B a vertex over the process's own 20 MB),
 * with room above that for the other readers. A face is its aiFace and
 * its index array, and the reader's own copy of both. */
#define IMPORT_BYTES_PER_VERTEX 48.0
#define IMPORT_BYTES_PER_FACE 64.0

bool mesh_import_fits(mesh_stream *s)
{
    double bytes = (double)s->vertices * IMPORT_BYTES_PER_VERTEX + (double)s->faces * IMPORT_BYTES_PER_FACE;
    char what[600];
    snprintf(what, sizeof what, "%s: importing %llu vertices and %llu faces", s->path, s->vertices, s->faces);
    return lanes_memory_fits(what, bytes, s->err) == LANES_OK;
}

bool mesh_ext_is(const char *path, const char *ext)
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
    if (mesh_ext_is(path, "obj"))
        return FMT_OBJ;
    if (mesh_ext_is(path, "off"))
        return FMT_OFF;
    if (mesh_ext_is(path, "ply"))
        return FMT_PLY;
    if (mesh_ext_is(path, "stl"))
        return FMT_STL;
    if (n >= 4 && memcmp(head, "ply", 3) == 0 && (head[3] == '\n' || head[3] == '\r'))
        return FMT_PLY;
    if (mesh_starts_solid(head, n))
        return FMT_STL;
    size_t i = 0;
    while (i < n && isspace(head[i]))
        i++;
    size_t j = i;
    while (j < n && !isspace(head[j]))
        j++;
    mesh_tok t = {(const char *)head + i, j - i};
    if (mesh_is_off_keyword(t))
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
            lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: no such file", path);
        else
            lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: %s", path, strerror(errno));
        return NULL;
    }
    if (S_ISDIR(st.st_mode)) {
        lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: is a directory, not a mesh file", path);
        return NULL;
    }
    /* A FIFO would block fopen until a writer comes (forever, for a
     * stray mkfifo), and Assimp reads devices by their stat size; a mesh
     * is a file. */
    if (!S_ISREG(st.st_mode)) {
        lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: not a regular file (a device, FIFO or socket)", path);
        return NULL;
    }
    if (st.st_size == 0) {
        lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: empty file", path);
        return NULL;
    }
    FILE *f = fopen(path, "rb");
    if (!f) {
        lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: cannot open: %s", path, strerror(errno));
        return NULL;
    }
    *size = (long long)st.st_size;
    return f;
}

lanes_status lanes_mesh_precheck(const char *path, lanes_error *err)
{
    double faces;
    return lanes_mesh_declared_faces(path, &faces, err);
}

lanes_status lanes_mesh_declared_faces(const char *path, double *faces, lanes_error *err)
{
    *faces = 0;
    /* the checkers below report through err, so it must exist */
    lanes_error local;
    if (!err) err = &local;
    long long size = 0;
    FILE *f = open_mesh(path, &size, err);
    if (!f) return err->status;
    mesh_stream *s = calloc(1, sizeof *s);
    if (!s) {
        fclose(f);
        return lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    }
    s->f = f;
    s->path = path;
    s->err = err;
    mesh_fill(s);
    mesh_format fmt = detect(path, s->buf, s->len);
    bool ok = true;
    switch (fmt) {
    case FMT_OBJ: ok = mesh_check_obj(s); break;
    case FMT_OFF: ok = mesh_check_off(s); break;
    case FMT_PLY: ok = mesh_check_ply(s); break;
    case FMT_STL: ok = mesh_check_stl(s, size); break;
    case FMT_OTHER: break;
    }
    if (ok && fmt != FMT_OTHER) ok = mesh_import_fits(s);
    if (ok) *faces = (double)s->faces;
    free(s->ln);
    free(s);
    fclose(f);
    return ok ? LANES_OK : err->status;
}
