/* One entry point from a user's scene argument to a lanes_scene.
 *
 * Compiled for the x86-64 baseline. */
#ifndef LANES_BUILD_SCENE_LOAD_H
#define LANES_BUILD_SCENE_LOAD_H

#include <stdbool.h>

#include "build/scene.h"

/* spec is, in this order of precedence:
 *   NULL or ""             the embedded default scene (no files needed);
 *   a built-in name        "default", "dragon", "sponza-bunny", ... (see
 *                          lanes_builtin_scene_info; a file of that name is
 *                          reached as ./name);
 *   a path ending in .json a scene file (build/SCENES.md);
 *   any other path         a mesh file (OBJ, PLY, OFF, STL, glTF, ...), shown
 *                          diffuse grey under one point light with a camera
 *                          framing it.
 * *out is initialized by the call; on failure it is empty and err says
 * which file, which line where there is one, and what is wrong, including
 * a scene too large to trace in the memory this process may use
 * (lanes_scene_reserve_triangles). */
lanes_status lanes_scene_load(const char *spec, lanes_scene *out, lanes_error *err);

#endif
