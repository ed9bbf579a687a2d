/* Whether two engines' answers on the same ray agree and, where they do
 * not, which of them is wrong, judged by the exact reference of `lanes
 * accuracy` (bench/accuracy_reference.h) rather than by a tolerance: for
 * `lanes compare` and the traversal tests.
 *
 * An answer is judged by what the float test that produced it can do. Each
 * triangle's three edge functions (the weights of its vertices) and the
 * distance t are computed in double, the sign of the edge functions exactly
 * where it matters, together with a bound on what rounding moves them by in
 * that test's float evaluation:
 *   Möller–Trumbore (lanes' fast and default modes, Embree 3): running-error
 *     bounds of the triple products it forms from o - v0, d and the rounded
 *     edges, gamma(10) times the sum of the magnitudes of their terms
 *     (both lanes' and Embree's arrangements have the same terms);
 *   watertight (lanes' robust mode): the sheared vertex coordinates carry
 *     gamma(4) of |p_x| + |s_x p_z| each, which the 2x2 edge functions then
 *     multiply, plus gamma(2) of their own products.
 * A triangle is then certainly crossed (every weight beyond its bound, one
 * sign), possibly crossed (within the bounds of a crossing, or exactly
 * crossed) or not crossed; a t is certainly or possibly within the ray's
 * interval the same way. An answer is wrong when
 *   - it reports a triangle that is not even possibly crossed, or possibly
 *     crossed only outside [tnear, tfar];
 *   - it reports a triangle that lies certainly beyond a certainly crossed
 *     one (not a tie: their t bounds do not overlap);
 *   - its t differs from the reported triangle's by more than twice its
 *     bound;
 *   - it reports a miss (or no occluder) where a triangle is certainly
 *     crossed within the interval;
 *   - it comes from a watertight test and reports a miss where the ray
 *     crosses a triangle exactly, within its bound of one edge only, and that
 *     edge is shared with one other triangle that the ray certainly enters
 *     from that edge: a watertight test gives one of the two.
 * Everything else that two engines disagree on is both acceptable: a true
 * tie or a true graze, by computation.
 *
 * Compiled for the x86-64 baseline. */
#ifndef LANES_BENCH_HITS_JUDGE_H
#define LANES_BENCH_HITS_JUDGE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "bench/accuracy_reference.h"
#include "build/bvh.h"
#include "build/scene.h"

/* Same primitive and t within 1e-4 relative, or both miss. */
bool hits_same(const lanes_hit *a, const lanes_hit *b);

typedef enum { JUDGE_MOLLER, JUDGE_WATERTIGHT } judge_test;

/* The float test of a lanes accuracy mode. */
judge_test judge_test_of(lanes_accuracy mode);

/* One engine's answer on one ray: a closest hit (prim LANES_NO_HIT for a
 * miss) or, with occlusion, whether something blocks the interval. */
typedef struct judge_answer {
    judge_test test;
    bool occlusion, occluded;
    uint32_t prim;
    float t;
} judge_answer;

typedef struct hits_verdicts {
    size_t lanes_wrong, embree_wrong, both_acceptable;
} hits_verdicts;

/* An edge's place in the list of shared edges: a hash of its two end
 * points (in either order) and the triangle and edge it belongs to. */
typedef struct judge_edge {
    uint64_t hash;
    uint32_t tri;
    uint32_t edge; /* the edge opposite vertex `edge` */
} judge_edge;

/* Read-only after hits_judge_init; safe to share between threads. */
typedef struct hits_judge {
    acc_ref ref;
    const lanes_scene *scene;
    judge_edge *edges; /* sorted by hash; NULL unless watertight answers are judged */
    size_t edge_count;
} hits_judge;

/* bvh is a BVH2 over the scene's triangles (its boxes guide the reference's
 * walk, and are checked to hold every triangle). watertight: answers of
 * the watertight test will be judged, which needs the list of shared
 * edges. Both must outlive the judge. */
lanes_status hits_judge_init(hits_judge *j, const lanes_scene *scene, const lanes_bvh2 *bvh,
                             bool watertight, lanes_error *err);
void hits_judge_free(hits_judge *j);

/* What the triangles near one ray say about it, for one test: the costly
 * part of a verdict (a walk over every triangle the ray passes near), the
 * same for every answer of that test on that ray. */
typedef struct judge_ray {
    double nearest_certain; /* the least t (plus its bound) of a certain crossing certainly in range */
    bool any_possible;      /* some triangle possibly crossed, possibly in range */
    bool forced;            /* a watertight test cannot miss (see above) */
} judge_ray;

judge_ray hits_judge_ray(const hits_judge *j, const lanes_ray *r, judge_test test);

/* Whether the answer is wrong for the ray (o, d, tnear, tfar of r), given
 * hits_judge_ray(j, r, a->test). */
bool hits_judge_answer(const hits_judge *j, const lanes_ray *r, const judge_ray *facts,
                       const judge_answer *a);
/* The same, with the ray's facts found here. */
bool hits_judge_wrong(const hits_judge *j, const lanes_ray *r, const judge_answer *a);

/* The facts of each ray of an array, for each test, found on first use:
 * the engines' answers on the same rays are judged against them once per
 * set, scheme and mode, and each walk is done once. Not thread-safe. */
typedef struct judge_cache {
    const lanes_ray *rays;
    size_t count;
    judge_ray *facts[2]; /* per judge_test */
    uint8_t *known[2];
} judge_cache;

bool judge_cache_init(judge_cache *c, const lanes_ray *rays, size_t count);
void judge_cache_free(judge_cache *c);

/* Counts one disagreement on ray i of the cache's rays: lanes wrong,
 * Embree wrong (both, when both are), or both acceptable. */
void hits_judge_pair(const hits_judge *j, judge_cache *c, size_t i, const judge_answer *lanes,
                     const judge_answer *embree, hits_verdicts *v);

#endif
