/* What a render of one scene needs, decided from the scene's content before
 * any ray is traced: passes nobody will use are not set up, data no shader
 * reads is not computed, and the accuracy mode is chosen (or recommended)
 * from the scene's coordinates. `lanes render --explain` prints it.
 *
 * Baseline code. */
#ifndef LANES_TRACE_SCENE_PLAN_H
#define LANES_TRACE_SCENE_PLAN_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

#include "build/scene.h"
#include "build/accuracy.h"

typedef struct lanes_scene_plan {
    /* what the scene holds */
    size_t triangles_of_kind[4]; /* by lanes_material_kind */
    size_t point_lights, area_lights;

    /* what the render does */
    bool shadow_rays;   /* lights exist and some triangle is diffuse */
    bool specular_pass; /* some triangle is a mirror or glass: reflected rays, specular packets */
    bool refraction;    /* some triangle is glass: refracted rays */
    bool hit_geometry;  /* some ray leaves a surface (shadow or specular), so hits need
                           their barycentrics (the hit point) and geometric normal */

    /* accuracy */
    lanes_accuracy accuracy;
    const char *accuracy_from;  /* "--accuracy", "the scene file", "the default" */
    double extent;              /* largest |coordinate| of any vertex */
    double diagonal;            /* of the scene's bounding box */
    double epsilon;             /* secondary-ray offset of fast and default modes */
    double epsilon_ulps;        /* epsilon in ulps of the largest coordinate */
    bool recommend_robust;      /* epsilon_ulps < LANES_PLAN_MIN_EPSILON_ULPS */
} lanes_scene_plan;

/* A hit point rebuilt from barycentrics, v0 + u e1 + v e2, carries about
 * three roundings of its largest coordinate, and the triangle test's t a few
 * more: an offset below 16 ulps of the scene's largest coordinate no longer
 * clears that error everywhere, and secondary rays start to hit the surface
 * they leave (see `lanes accuracy`, column self_hits, for the measured
 * rates as a mesh moves away from the origin). With the default epsilon
 * (1e-5 of the diagonal) that happens when coordinates exceed about 5 times
 * the scene's diagonal (1e-5 * 2^23 / 16). */
#define LANES_PLAN_MIN_EPSILON_ULPS 16.0

/* requested: the --accuracy / API choice, or -1 to take the scene file's
 * (scene->accuracy), or else LANES_ACCURACY_DEFAULT. */
void lanes_scene_plan_make(const lanes_scene *scene, int requested, lanes_scene_plan *plan);

/* Prints what was switched on and off, and why. */
void lanes_scene_plan_explain(const lanes_scene_plan *plan, FILE *out);

#endif
