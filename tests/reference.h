/* Independent double-precision references for the ray/box and ray/triangle
 * kernels, with a "margin" per case: how far the case sits from a decision
 * boundary, relative to the magnitudes a float evaluation works with.
 *
 * Why margins: the kernels decide in float, so a case whose exact answer
 * hinges on a difference below a few float roundings may legitimately go
 * either way. Such a case is "in the tolerance band" when its margin is below
 * REF_BAND; disagreements there are counted and bounded, everywhere else
 * they are failures. A margin of +inf marks a decision that float code makes
 * exactly (an invalid ray, an empty box, a slab test on a zero direction, a
 * quantity whose every term is zero): no tolerance applies to it.
 *
 * Compiled for the x86-64 baseline; nothing here knows about the kernels'
 * code or layouts beyond the public conventions of trace/kernels.h. */
#ifndef LANES_TESTS_REFERENCE_H
#define LANES_TESTS_REFERENCE_H

#include <stdbool.h>
#include <stdint.h>

/* A case is in the tolerance band when its margin is below REF_BAND. The
 * kernels' own rounding flips decisions only below roughly 10 units of
 * roundoff (10 * 2^-24 = 6e-7 relative), so 1e-5 leaves a factor of ~16. */
#define REF_BAND 1e-5
/* In-band disagreements may make up at most this fraction of the cases of a
 * kernel that were not built to sit on a boundary (random rays at random
 * primitives rarely land in the band at all). */
#define REF_BAND_MAX_FRACTION 1e-4
/* Cases built on purpose at a boundary (rays aimed at edges, vertices and
 * faces, moved by a few floats; t bounds set to the hit distance; flat
 * boxes) land in the band by design, and there float rounding is a coin
 * toss. Their in-band disagreements may make up at most this fraction of
 * their in-band cases: a kernel with a systematic bias (an exclusive
 * boundary, a shrunken box) flips far more of them. */
#define REF_BAND_TARGETED_FRACTION 0.25
/* Magnitudes below this are treated as "zero-ish": float results there lose
 * relative precision to underflow, so gaps are measured against this floor. */
#define REF_TINY 1e-30

/* A ray as the caller writes it, before lanes_rays_prepare(). */
typedef struct ref_ray {
    float o[3], d[3];
    float tnear, tfar;
} ref_ray;

/* The public validity rule: finite o and d, non-NaN tnear and tfar, d != 0. */
bool ref_ray_valid(const ref_ray *r);

typedef struct ref_box_result {
    bool hit;
    double tentry; /* max(tnear, entry distance), when hit */
    double margin; /* relative distance from the hit/miss boundary */
} ref_box_result;

/* Closed box [lo, hi]; an axis with lo > hi (or a NaN bound) makes it empty. */
ref_box_result ref_box(const ref_ray *r, const float lo[3], const float hi[3]);

enum { REF_MOLLER = 0, REF_WATERTIGHT = 1 };

typedef struct ref_tri_result {
    bool hit;
    bool degenerate; /* zero area: never hit */
    bool parallel;   /* d lies in the triangle's plane direction (d . n == 0) */
    double t, u, v;  /* u, v: barycentric weights of v1 and v2 (valid unless parallel) */
    /* Per algorithm (REF_MOLLER, REF_WATERTIGHT), because the two evaluate
     * different expressions whose rounding scales differently. */
    double margin[2];
    /* Forward-error scales in units of the roundoff u = 2^-24, absolute:
     * the algorithm's |t - t_ref| is expected below c * u * tscale and
     * |u - u_ref| below c * u * uscale for a small constant c. */
    double tscale[2], uscale[2], vscale[2];
} ref_tri_result;

/* Two-sided; the boundary counts as inside; hit iff t in [tnear, tfar]. */
ref_tri_result ref_tri(const ref_ray *r, const float v0[3], const float v1[3], const float v2[3]);

/* The decisions alone, without margins: for the frustum tests, which ask
 * whether any ray of a packet hits and so evaluate many more pairs. */
bool ref_box_hit(const ref_ray *r, const float lo[3], const float hi[3]);
bool ref_tri_hit(const ref_ray *r, const float v0[3], const float v1[3], const float v2[3]);

/* Distance in units in the last place between two floats, through the
 * monotone integer ordering of their bit patterns (-0 and +0 coincide). */
uint32_t ref_ulp_distance(float a, float b);

#endif
