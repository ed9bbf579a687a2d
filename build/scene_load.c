/* The scene argument: built-in name, scene file or mesh file.
 *
 * Compiled for the x86-64 baseline. */
#define _POSIX_C_SOURCE 200809L /* stat */

#include "build/scene_load.h"

#include "build/memory_limit.h"
#include "build/mesh_import.h"
#include "build/scene_file.h"
#include "build/scenes_builtin.h"

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

static bool ends_with_ci(const char *s, const char *suffix)
{
    size_t n = strlen(s), k = strlen(suffix);
    return n >= k && strcasecmp(s + n - k, suffix) == 0;
}

static lanes_status mesh_scene(const char *path, lanes_scene *out, lanes_error *err)
{
    lanes_status status;
    lanes_scene_init(out);
    if ((status = lanes_scene_limit_to_memory(out, err)) != LANES_OK) return status;
    const char *slash = strrchr(path, '/');
    snprintf(out->name, sizeof out->name, "%s", slash ? slash + 1 : path);
    lanes_material grey;
    memset(&grey, 0, sizeof grey);
    snprintf(grey.name, sizeof grey.name, "default");
    grey.kind = LANES_MAT_DIFFUSE;
    grey.color[0] = grey.color[1] = grey.color[2] = 0.8f;
    grey.ior = 1.5f;
    uint32_t mat;
    lanes_error why;
    if ((status = lanes_scene_add_material(out, &grey, &mat, &why)) != LANES_OK) {
        lanes_error_set(err, status, "%s: %s", path, why.message);
        lanes_scene_free(out);
        return status;
    }
    if ((status = lanes_mesh_import(out, path, NULL, mat, err)) != LANES_OK) {
        lanes_scene_free(out);
        return status;
    }
    lanes_scene_frame_camera(out);
    /* A light over the viewer's shoulder, bright enough that the mesh is
     * lit at about unit irradiance whatever its size. */
    lanes_camera *c = &out->camera;
    double d2 = 0.0;
    for (int a = 0; a < 3; a++)
        d2 += ((double)c->eye[a] - c->target[a]) * ((double)c->eye[a] - c->target[a]);
    double up = 0.5 * sqrt(d2);
    /* The mesh itself was checked on import; what can still fail is the
     * camera and light placed for it, whose intensity grows with the
     * squared distance: past about 1e18 units that overflows a float, and
     * validation would then blame a "non-finite point light" that is not
     * in the file. */
    double limit = FLT_MAX / 2.0;
    if (!(1.5 * d2 < limit) || !(fabs(c->eye[0]) + up < limit) || !(fabs(c->eye[1]) + up < limit)) {
        status = lanes_error_set(err, LANES_ERR_BAD_INPUT,
                                 "%s: the mesh is too large to frame (coordinates or extent beyond about "
                                 "1e18): the light's intensity would overflow a float",
                                 path);
        lanes_scene_free(out);
        return status;
    }
    lanes_point_light l = {{c->eye[0] + (float)up, c->eye[1] + (float)up, c->eye[2]},
                           {(float)(1.5 * d2), (float)(1.5 * d2), (float)(1.5 * d2)}};
    if ((status = lanes_scene_add_point_light(out, &l, &why)) != LANES_OK ||
        (status = lanes_scene_validate(out, &why)) != LANES_OK) {
        lanes_error_set(err, status, "%s: %s", path, why.message);
        lanes_scene_free(out);
        return status;
    }
    return LANES_OK;
}

lanes_status lanes_scene_load(const char *spec, lanes_scene *out, lanes_error *err)
{
    if (!spec || !*spec)
        return lanes_builtin_scene("default", out, err);
    for (size_t i = 0; i < lanes_builtin_scene_count(); i++)
        if (strcmp(spec, lanes_builtin_scene_info(i)->name) == 0)
            return lanes_builtin_scene(spec, out, err);
    if (ends_with_ci(spec, ".json"))
        return lanes_scene_file_load(spec, out, err);
    struct stat st;
    if (stat(spec, &st) != 0) {
        lanes_scene_init(out);
        if (errno == ENOENT && !strchr(spec, '/') && !strchr(spec, '.'))
            /* A bare word: most likely a mistyped scene name. */
            return lanes_builtin_scene(spec, out, err);
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: %s", spec,
                               errno == ENOENT ? "no such file" : strerror(errno));
    }
    return mesh_scene(spec, out, err);
}
