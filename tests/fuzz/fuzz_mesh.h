/* The mesh-file harness shared by fuzz_mesh_<format>.c: each target only
 * names the file extension, which is what makes the loader (and Assimp)
 * pick the format.
 *
 * lanes_mesh_read takes a path (its pre-checks stream from a FILE, and
 * Assimp opens the file itself), so every input is written to a scratch
 * file first; that costs microseconds against the milliseconds of an
 * import. A mesh that loads is then loaded again the way the CLI does
 * (lanes_scene_load: mesh, default material, light, framed camera), which
 * must also succeed with a valid scene or fail with a message. */
#ifndef LANES_TESTS_FUZZ_MESH_H
#define LANES_TESTS_FUZZ_MESH_H

#include "tests/fuzz/fuzz_common.h"

#include "build/mesh_import.h"
#include "build/scene_load.h"

static inline int fuzz_mesh_one(const char *ext, const uint8_t *data, size_t size)
{
    char name[32], path[512];
    snprintf(name, sizeof name, "input.%s", ext);
    fuzz_write(path, sizeof path, name, data, size);

    lanes_mesh m;
    lanes_error err = {0};
    if (lanes_mesh_read(path, &m, &err) != LANES_OK) {
        fuzz_check_failure(&err, path);
        return 0;
    }
    fuzz_check_mesh(&m, path);
    lanes_mesh_free(&m);

    lanes_scene s;
    memset(&err, 0, sizeof err);
    if (lanes_scene_load(path, &s, &err) == LANES_OK) {
        fuzz_check_scene(&s, path);
        lanes_scene_free(&s);
    } else {
        fuzz_check_failure(&err, path);
    }
    return 0;
}

/* Defines the libFuzzer entry point for one extension. */
#define LANES_FUZZ_MESH_TARGET(ext)                                                              \
    int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);                                \
    int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)                                 \
    {                                                                                            \
        return fuzz_mesh_one(ext, data, size);                                                   \
    }

#endif
