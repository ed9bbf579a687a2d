/* Shared pieces of the libFuzzer targets in tests/fuzz/: the contract
 * checks and a scratch directory for loaders that only take a path.
 *
 * The contract every loader must keep, whatever the bytes: either success
 * with data every consumer can rely on, or failure with a message that
 * names the input file and says what is wrong. A violation calls
 * __builtin_trap(), so libFuzzer reports it as a crash and saves the input.
 * Crashes, leaks and undefined behaviour inside the loader are reported by
 * ASan/UBSan, hangs by -timeout and absurd allocations by -malloc_limit_mb. */
#ifndef LANES_TESTS_FUZZ_COMMON_H
#define LANES_TESTS_FUZZ_COMMON_H

#define _POSIX_C_SOURCE 200809L /* mkdtemp, strnlen */

#include "build/scene.h"

#include <dirent.h>
#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* Everything here is static inline: each target uses only some of it. */

#if defined(__GNUC__)
__attribute__((format(printf, 1, 2)))
#endif
static inline _Noreturn void fuzz_violation(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fputs("fuzz: contract violated: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
    __builtin_trap();
}

/* A failure must say which file and what is wrong: the message contains
 * `name` and has more to it than the name alone. */
static inline void fuzz_check_failure(const lanes_error *err, const char *name)
{
    size_t n = strnlen(err->message, sizeof err->message);
    if (n == sizeof err->message)
        fuzz_violation("the error message is not NUL-terminated");
    if (n == 0)
        fuzz_violation("failure without a message (input %s)", name);
    if (!strstr(err->message, name))
        fuzz_violation("the message does not name the file %s: \"%s\"", name, err->message);
    if (n < strlen(name) + 3)
        fuzz_violation("the message names the file but no problem: \"%s\"", err->message);
}

/* What every consumer of a scene relies on, checked here independently of
 * lanes_scene_validate and then by it. */
static inline void fuzz_check_scene(const lanes_scene *s, const char *name)
{
    if (s->triangle_count == 0)
        fuzz_violation("%s: success with an empty scene", name);
    if (s->triangle_count > LANES_SCENE_MAX_TRIANGLES)
        fuzz_violation("%s: %zu triangles, more than the limit", name, s->triangle_count);
    if (s->material_count == 0)
        fuzz_violation("%s: triangles but no material", name);
    for (size_t i = 0; i < 9 * s->triangle_count; i++)
        if (!isfinite(s->verts[i]))
            fuzz_violation("%s: triangle %zu has a non-finite vertex", name, i / 9);
    for (size_t i = 0; i < s->triangle_count; i++)
        if (s->material_of[i] >= s->material_count)
            fuzz_violation("%s: triangle %zu has material %u of %zu", name, i,
                           (unsigned)s->material_of[i], s->material_count);
    if (s->camera.width <= 0 || s->camera.height <= 0)
        fuzz_violation("%s: camera size %dx%d", name, s->camera.width, s->camera.height);
    lanes_error err = {0};
    if (lanes_scene_validate(s, &err) != LANES_OK)
        fuzz_violation("%s: loaded, but lanes_scene_validate refuses it: %s", name, err.message);
}

static inline void fuzz_check_mesh(const lanes_mesh *m, const char *name)
{
    if (m->triangle_count == 0 || m->vertex_count == 0)
        fuzz_violation("%s: success with an empty mesh (%zu triangles, %zu vertices)", name,
                       m->triangle_count, m->vertex_count);
    for (size_t i = 0; i < 3 * m->vertex_count; i++)
        if (!isfinite(m->positions[i]))
            fuzz_violation("%s: vertex %zu is not finite", name, i / 3);
    for (size_t i = 0; i < 3 * m->triangle_count; i++)
        if (m->indices[i] >= m->vertex_count)
            fuzz_violation("%s: triangle %zu refers to vertex %u of %zu", name, i / 3,
                           (unsigned)m->indices[i], m->vertex_count);
}

/* ---- a private scratch directory, removed at exit ---- */

static char fuzz_dir_path[256];

static inline void fuzz_remove_dir(void)
{
    DIR *d = opendir(fuzz_dir_path);
    if (d) {
        struct dirent *e;
        while ((e = readdir(d)) != NULL) {
            if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0)
                continue;
            char p[512];
            snprintf(p, sizeof p, "%s/%s", fuzz_dir_path, e->d_name);
            unlink(p);
        }
        closedir(d);
    }
    rmdir(fuzz_dir_path);
}

/* Created once per process, so fuzzers running side by side (ctest -j,
 * -jobs=N) never share a file. */
static inline const char *fuzz_dir(void)
{
    if (!fuzz_dir_path[0]) {
        const char *tmp = getenv("TMPDIR");
        snprintf(fuzz_dir_path, sizeof fuzz_dir_path, "%s/lanes-fuzz-XXXXXX",
                 tmp && *tmp ? tmp : "/tmp");
        if (!mkdtemp(fuzz_dir_path)) {
            perror("fuzz: mkdtemp");
            abort();
        }
        atexit(fuzz_remove_dir);
    }
    return fuzz_dir_path;
}

/* Writes the bytes to <scratch>/name; the path goes to path[cap]. */
static inline const char *fuzz_write(char *path, size_t cap, const char *name, const void *data,
                                     size_t size)
{
    snprintf(path, cap, "%s/%s", fuzz_dir(), name);
    FILE *f = fopen(path, "wb");
    if (!f || (size > 0 && fwrite(data, 1, size, f) != size) || fclose(f) != 0) {
        perror(path);
        abort();
    }
    return path;
}

#endif
