/* The measurements behind `lanes accuracy`, shared by the command and by
 * tests/test_accuracy.c: a closed mesh placed at a size and a translation
 * ("a world"), points inside it, rays that must hit and rays that just miss,
 * and what each accuracy mode at each kernel set makes of them:
 *
 *   leaks       rays from interior points (at least ACC_CLEARANCE * size from
 *               the surface) that report no hit, although every such ray
 *               crosses the closed surface: in random directions, and aimed
 *               at mesh vertices and edge midpoints (where a test that is
 *               not watertight loses rays: the hard case, which random
 *               directions meet about once in 10^6 rays);
 *   false hits  rays that the exact reference says miss the whole mesh, by a
 *               few float ulps beside a silhouette edge, but that report a hit;
 *   t error     for the hits of the leak rays, lanes' t against the exact
 *               distance to the plane of the triangle lanes reported, as an
 *               integer ulp distance from that distance rounded to float;
 *   self hits   reflected and transmitted rays spawned at those hits with
 *               lanes_offset_origin that hit the triangle they leave;
 *   Mrays/s     single-thread closest-hit throughput of the leak rays.
 *
 * Everything is deterministic: ray i of a world depends only on the world's
 * seed and on i, so a shorter run traces a prefix of a longer one and counts
 * do not depend on the number of threads.
 *
 * Compiled for the x86-64 baseline. */
#ifndef LANES_BENCH_ACCURACY_MEASURE_H
#define LANES_BENCH_ACCURACY_MEASURE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "bench/accuracy_reference.h"
#include "build/bvh.h"
#include "build/scene.h"
#include "trace/kernels.h"

/* Interior points per world. Rays i*ACC_RAYS_PER_POINT .. (i+1)*ACC_RAYS_PER_POINT-1
 * share an origin (point i modulo the points found), so they can also be
 * traced as one packet. */
#define ACC_POINTS 1024
#define ACC_RAYS_PER_POINT 256
/* Interior points keep at least this fraction of the size from the surface. */
#define ACC_CLEARANCE 1e-3
/* The default size: the mesh's bounding-box diagonal. */
#define ACC_DEFAULT_SIZE 100.0

/* Ulp histogram: bins 0..63 count exact distances, then bin 64+k counts
 * distances in [2^(6+k), 2^(7+k)); the last bin takes everything above. */
#define ACC_ULP_EXACT 64
#define ACC_ULP_BINS (ACC_ULP_EXACT + 26)

/* ---- meshes ---------------------------------------------------------- */

/* Closedness: every edge in exactly two triangles, once in each direction. */
typedef struct acc_closure {
    size_t triangles, edges;
    size_t boundary;     /* edges in one triangle */
    size_t nonmanifold;  /* edges in three or more */
    size_t misoriented;  /* edges in two triangles that run the same way */
    size_t degenerate;   /* triangles that repeat a vertex index */
} acc_closure;

lanes_status acc_mesh_closure(const lanes_mesh *m, acc_closure *c, lanes_error *err);
bool acc_closure_closed(const acc_closure *c);
/* "12 boundary edges, 1 misoriented edge" */
void acc_closure_describe(const acc_closure *c, char *buf, size_t size);

/* A closed mesh to measure, by spec: a built-in object name (sphere, bunny,
 * dragon, ...; sphere at icosphere level 4) or a mesh file. A built-in
 * object whose boundary is a few simple loops (under 1% of its edges; the
 * CGAL dragon has two triangular holes) is closed by filling each loop with
 * a fan, and *note says so; anything else that is not closed is an error
 * naming the spec and what is wrong. note may be NULL. */
lanes_status acc_mesh_load(const char *spec, bool is_file, lanes_mesh *out, char *note, size_t note_size,
                           lanes_error *err);

/* ---- worlds ---------------------------------------------------------- */

typedef struct acc_world {
    char name[64];
    double size, translation;
    uint64_t seed;
    lanes_scene scene;      /* the mesh scaled to `size`, centred, plus `translation`
                             * on every coordinate, rounded to float */
    lanes_bvh2 bvh2;
    lanes_wbvh wide[3];     /* widths 4, 8, 16; width 0 where not built */
    acc_ref ref;
    float eps;              /* lanes_scene_epsilon of the scene */
    uint32_t *adjacent;     /* adjacent[3t+e]: the triangle across edge e (v_e -> v_e+1) of t */
    float (*points)[3];
    size_t point_count;     /* 0: the rounded mesh has no interior left (n/a) */
    size_t point_candidates;
    lanes_ray *misses;      /* rays the reference says miss everything (unprepared) */
    size_t miss_count, miss_attempts;
} acc_world;

/* Places the (closed) mesh and builds what the measurements need: the BVH2,
 * the wide BVHs of the widths whose acc_width_bit is in width_mask, the
 * reference and the interior points.
 * threads: 0 for all cores. */
lanes_status acc_world_build(acc_world *w, const char *name, const lanes_mesh *mesh, double size,
                             double translation, unsigned width_mask, int threads, uint64_t seed,
                             lanes_error *err);
/* Generates `count` rays that just miss (b); fewer when the mesh offers too
 * few silhouette edges that the exact test confirms as misses. */
lanes_status acc_world_misses(acc_world *w, size_t count, int threads, lanes_error *err);
void acc_world_free(acc_world *w);
const lanes_wbvh *acc_world_wide(const acc_world *w, int width);
static inline unsigned acc_width_bit(int width) { return width == 4 ? 1u : width == 8 ? 2u : width == 16 ? 4u : 0u; }

/* Leak ray i, unprepared (tnear 0, tfar +inf). The world must have points. */
void acc_leak_ray(const acc_world *w, uint64_t i, lanes_ray *r);
/* Aimed leak ray i: from the same point as leak ray i, towards a vertex
 * (odd i) or the float midpoint of an edge (even i) of a random triangle;
 * d = target - origin in float, so the ray passes within a rounding of it. */
void acc_aimed_ray(const acc_world *w, uint64_t i, lanes_ray *r);

/* ---- measuring ------------------------------------------------------- */

typedef enum acc_via {
    ACC_VIA_WIDE = 0,  /* k->trace_wide over the wide BVH of k->wide_width */
    ACC_VIA_BVH2,      /* k->trace_bvh2 */
    ACC_VIA_PACKET,    /* k->trace_packet, partition scheme, no frustum: each
                        * packet is the ACC_RAYS_PER_POINT rays of one point */
    ACC_VIA_COUNT
} acc_via;
const char *acc_via_name(acc_via v);

typedef struct acc_counts {
    uint64_t rays, leaks;
    uint64_t aimed_rays, aimed_leaks;
    uint64_t t_samples, t_hist[ACC_ULP_BINS];
    uint64_t self_rays, self_hits;
    uint64_t miss_rays, false_hits;
} acc_counts;

typedef struct acc_job {
    const lanes_kernels *k;
    lanes_accuracy mode;
    acc_via via;
    uint64_t first, count; /* leak rays first .. first+count-1 */
    bool aimed;            /* the aimed rays instead (counted apart; no t error, no self hits) */
    bool t_error;          /* (c) over their hits */
    uint64_t self_from;    /* (d): two secondary rays at each hit of the first self_from leak rays */
    bool false_hits;       /* (b) over the world's misses */
    int threads;           /* 0: all cores */
} acc_job;

/* Adds the job's counts to *out. Fails only when memory runs out or the
 * world lacks the wide BVH the set needs. */
lanes_status acc_measure(const acc_world *w, const acc_job *job, acc_counts *out, lanes_error *err);

/* Closest-hit throughput of leak rays 0 .. rays-1 through k->trace_wide on
 * one thread (the caller's), median of reps runs, in Mrays/s; NaN when the
 * world has no points or memory runs out. */
double acc_time_wide(const acc_world *w, const lanes_kernels *k, lanes_accuracy mode, size_t rays, int reps);

int acc_ulp_bin(uint64_t ulps);
uint64_t acc_ulp_bin_low(int bin);
/* The smallest bin low bound below or at which fraction p of the samples
 * lie (exact below ACC_ULP_EXACT); NaN with no samples. */
double acc_ulp_percentile(const acc_counts *c, double p);


#endif
