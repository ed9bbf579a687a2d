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
    size_t triangles_of_kind[4]; /* by lanes_material_whitted_kind */
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
    bool has_vertices;          /* some vertex is finite (else the sizes are 0) */
    double extent;              /* largest |coordinate| of any vertex */
    double diagonal;            /* of the scene's bounding box */
    double reach;               /* diagonal of the box of the vertices and the camera's eye:
                                   the longest distance a triangle test meets */
    double longest_edge;        /* of any triangle */
    double epsilon;             /* secondary-ray offset of fast and default modes */
    double epsilon_ulps;        /* epsilon in ulps of the largest coordinate */
    double offset_bound;        /* the largest offset robust mode gives a hit point here */
    bool recommend_robust;      /* epsilon < offset_bound */
} lanes_scene_plan;

/* When the fixed offset of fast and default modes is safe: robust mode
 * moves a secondary origin out of the rounding-error box of its hit point
 * (lanes_offset_origin, trace/shading.h), and that box grows with the
 * coordinates. offset_bound is the offset it would give the worst point of
 * the scene: twice the box's diagonal, a coordinate as large as `extent`
 * (unit roundoff u of it) with gamma(3) of the longest edge, plus the one
 * float it steps out on each axis. Fast and default modes are safe when
 * their epsilon is at least that; below it they are recommended robust.
 * With 1e-5 of the diagonal as epsilon the verdict turns at coordinates of
 * 25 to 30 diagonals (1e-5 / (4 sqrt(3) u) to 1e-5 / (5.2 u)). On the
 * mirror-box scene of tests/test_scale_sweep.c it turns at 26 diagonals;
 * default mode still renders right at 87 and first fails at 261. */

/* requested: the --accuracy / API choice, or -1 to take the scene file's
 * (scene->accuracy), or else LANES_ACCURACY_DEFAULT. */
void lanes_scene_plan_make(const lanes_scene *scene, int requested, lanes_scene_plan *plan);

/* LANES_ERR_BAD_INPUT, with a message naming the size and the limit, when
 * the plan's accuracy mode cannot trace the scene at its size, its reach
 * taking in the camera (the limits of build/accuracy.h); LANES_OK for a
 * scene without a finite vertex. */
lanes_status lanes_scene_plan_check(const lanes_scene_plan *plan, lanes_error *err);

/* Prints what was switched on and off, and why. */
void lanes_scene_plan_explain(const lanes_scene_plan *plan, FILE *out);

#endif
