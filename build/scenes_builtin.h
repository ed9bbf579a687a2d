/* Built-in scenes and objects, generated deterministically (the only
 * randomness is a fixed-seed PCG32 in scenes_builtin.c), and the mesh
 * operations they use. Scenes and their mapping to the thesis' Table 4.1
 * are described in build/SCENES.md.
 *
 * Compiled for the x86-64 baseline. */
#ifndef LANES_BUILD_SCENES_BUILTIN_H
#define LANES_BUILD_SCENES_BUILTIN_H

#include <stdbool.h>
#include <stddef.h>

#include "build/scene.h"

typedef struct lanes_builtin_info {
    const char *name;
    const char *description;
    bool needs_meshes; /* reads CGAL meshes fetched by cmake/fetch_meshes.sh */
} lanes_builtin_info;

size_t lanes_builtin_scene_count(void);
const lanes_builtin_info *lanes_builtin_scene_info(size_t i);
/* Fills *out (initialized by the call) with the named scene. */
lanes_status lanes_builtin_scene(const char *name, lanes_scene *out, lanes_error *err);

/* The fetched meshes: $LANES_MESH_DIR if set and not empty, else the
 * directory configured at build time (<source>/out/meshes by default). */
const char *lanes_mesh_dir(void);
/* True when every mesh the built-in scenes use is present there. */
bool lanes_builtin_meshes_available(void);

/* Objects usable by name (scene files' "builtin"): primitives fitting
 * [-1,1]^3 ("sphere" radius 1 at the origin, "box" [-1,1]^3, "plane" the
 * square [-1,1]^2 in xz at y = 0 facing +y, "cylinder" radius 1 along y
 * from -1 to 1 with caps) and the CGAL meshes ("bunny", "dragon",
 * "armadillo", "elephant") normalized: centered on the y axis, standing on
 * y = 0, facing +z, largest extent 1. detail: icosphere level / cylinder
 * segments / Loop subdivision steps for meshes; -1 for the default. */
lanes_status lanes_builtin_object(const char *name, int detail, lanes_mesh *out, lanes_error *err);
/* The triangles lanes_builtin_object(name, detail) makes, known before it
 * makes them (for a CGAL mesh, from its file's declared faces: at least
 * that many); 0 where it would fail. */
double lanes_builtin_object_triangles(const char *name, int detail);
/* Names, comma-separated, for messages. */
const char *lanes_builtin_object_names(void);

/* An area light plus, when `visible`, its parallelogram as two triangles
 * with an emissive material of the same emission (so camera and mirror
 * rays see the light; shadow rays toward a point on it must stop short of
 * it). */
lanes_status lanes_scene_add_area_light_quad(lanes_scene *s, const lanes_area_light *l, bool visible,
                                             lanes_error *err);

#endif
