/* The double-precision reference of `lanes accuracy`: which triangles of a
 * float mesh a float ray really meets, decided exactly for the float inputs,
 * independently of the kernels under test.
 *
 * Decisions are exact. The three edge functions (signed volumes
 * d . ((B-o) x (C-o)) ...) and the orientation of the origin against the
 * triangle's plane are evaluated in double, and wherever the double value is
 * within its error bound of 0 they are evaluated again exactly, in expansion
 * arithmetic (sums of non-overlapping doubles, Shewchuk 1997), whose sign is
 * the sign of the exact value. So "the ray passes one float ulp beside an
 * edge" and "the ray passes exactly through the edge" are told apart.
 * Distances t are doubles: t = [a, b, c] / (U + V + W) with a = A - o, ...,
 * a few double roundings from the exact t (relative error ~1e-15 unless the
 * ray grazes the plane, far below the 6e-8 of one float ulp).
 *
 * The walk reads the BVH2 that lanes built (its node boxes only); every box
 * is widened outward by far more than the rounding of a double slab test,
 * and the tree is checked, once, to contain each triangle in every box above
 * it. A builder bug therefore cannot hide a triangle from the reference.
 *
 * Compiled for the x86-64 baseline. */
#ifndef LANES_BENCH_ACCURACY_REFERENCE_H
#define LANES_BENCH_ACCURACY_REFERENCE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "build/bvh.h"
#include "build/scene.h"

/* One float ray against one float triangle (vertices v[0..8]). */
typedef struct acc_tri_result {
    bool crosses;  /* the ray's line meets the closed triangle (boundary included);
                    * false for a line in the triangle's plane and for zero area */
    int t_sign;    /* exact sign of t where the line meets the plane (0: o on the plane) */
    double t;      /* that t in double; NaN when the line is parallel to the plane */
} acc_tri_result;

acc_tri_result acc_ref_tri(const float o[3], const float d[3], const float *v);

/* The reference over one mesh: the scene's triangles through the BVH2 built
 * over them. Read-only after acc_ref_init; safe to share between threads. */
typedef struct acc_ref {
    const lanes_bvh2 *bvh;
    const float *verts; /* scene->verts: triangle i is verts[9i .. 9i+8] */
} acc_ref;

/* Fails (with a message) when some triangle lies outside a box above it. */
lanes_status acc_ref_init(acc_ref *r, const lanes_bvh2 *bvh, const lanes_scene *scene, lanes_error *err);

/* Calls visit(ctx, prim) for each triangle of every leaf whose box the ray
 * o + t d, t >= 0, touches: with widen = 0 a superset of the triangles the
 * ray meets (the boxes are widened beyond the walk's own rounding); with
 * widen > 0 also those it passes within about widen times their distance
 * from o. visit returns true to stop the walk (the result). */
bool acc_ref_walk(const acc_ref *r, const float o[3], const float d[3], double widen,
                  bool (*visit)(void *ctx, uint32_t prim), void *ctx);
/* Does the ray o + t d, t >= 0, meet any triangle? */
bool acc_ref_any(const acc_ref *r, const float o[3], const float d[3]);
/* Triangles the ray meets at t > 0 (a crossing through a shared edge or
 * vertex is counted once per triangle). */
size_t acc_ref_crossings(const acc_ref *r, const float o[3], const float d[3]);
/* Is some triangle closer than dist to p? */
bool acc_ref_near(const acc_ref *r, const double p[3], double dist);

/* How many evaluations fell back to exact arithmetic, for the report
 * (process-wide, approximate under threads). */
uint64_t acc_ref_exact_fallbacks(void);

#endif
