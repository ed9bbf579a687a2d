/* Many materials for a scene, to measure what shading coherence is worth
 * (Afra et al. 2016 use scenes of 36 and 111 materials): n generated
 * materials named "@mat0000", ... (the reserved prefix) replace the
 * scene's own on every triangle that is not emissive, assigned
 *   - per object: each run of consecutive triangles that share a material
 *     (an object as the scene added it) takes one;
 *   - per cluster: triangles whose centroids fall in the same cell of a
 *     64^3 grid over the scene's bounds take one (spatially coherent);
 *   - at random: each triangle its own draw.
 * The choice is a hash of the run, cell or triangle: the same scene gives
 * the same assignment. The materials are the shader library's kinds in
 * turn, with their own colors: by index mod 8 diffuse, plastic, diffuse
 * with a solid texture (checker, noise, marble, wood in turn), conductor,
 * diffuse, textured plastic, diffuse, mirror. Emissive triangles (lights)
 * keep theirs.
 *
 * Compiled for the x86-64 baseline. */
#ifndef LANES_BUILD_MATERIAL_ASSIGN_H
#define LANES_BUILD_MATERIAL_ASSIGN_H

#include "build/scene.h"

typedef enum lanes_material_assign {
    LANES_ASSIGN_OBJECT = 0,
    LANES_ASSIGN_CLUSTER,
    LANES_ASSIGN_RANDOM,
    LANES_ASSIGN_COUNT
} lanes_material_assign;

const char *lanes_material_assign_name(lanes_material_assign a);
/* -1 for an unknown name */
int lanes_material_assign_from_name(const char *name);

/* The most materials the generator makes: the stream renderer's sort
 * takes at most this many (trace/material_sort.h) with the scene's own. */
#define LANES_ASSIGN_MAX_MATERIALS 65000

/* Adds n materials (1 .. LANES_ASSIGN_MAX_MATERIALS) and assigns them;
 * the scene's own materials stay defined (its lights' among them). Fails,
 * leaving the scene's triangles as they were, on a bad n or mode or when
 * the materials cannot be added. */
lanes_status lanes_scene_assign_materials(lanes_scene *scene, int n, lanes_material_assign mode, lanes_error *err);

#endif
