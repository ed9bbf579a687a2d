/* The table through which every caller reaches the hot kernels, and what
 * they take besides the data layouts (build/layout.h). The kernels themselves are written once (trace/kernels/<family>_kernels.c)
 * and compiled per instruction set; each set fills one lanes_kernels table.
 *
 * Compiled for the x86-64 baseline: no intrinsics here.
 *
 * Conventions shared by every kernel:
 * - A ray is o + t*d for t in the closed interval [tnear, tfar].
 * - Boxes are closed: a ray touching a face, edge or corner hits.
 *   A box with min > max on any axis is empty and never hit.
 * - Rays pass through lanes_rays_prepare() first. It computes reciprocal
 *   directions and turns every invalid ray (NaN or infinite component in o or
 *   d, NaN tnear or tfar, d = 0) into an inactive one (tnear = +inf,
 *   tfar = -inf), which no kernel ever reports as a hit. It also clamps
 *   infinite tnear and tfar to -FLT_MAX and FLT_MAX (see ray_kernels.c).
 * - Hit masks are bit arrays (build/layout.h).
 * - Where a kernel writes per-hit values (t, u, v), it writes them only for
 *   hits; the caller's values for misses are left untouched.
 * - Arrays are aligned and padded (build/layout.h), so a full-width load
 *   from any element below the count stays inside the allocation. Results
 *   past the count are never written.
 * - stats, when not NULL, accumulates lane accounting. With NULL the kernel
 *   runs a copy of its body with the counting compiled out.
 */
#ifndef LANES_TRACE_KERNELS_H
#define LANES_TRACE_KERNELS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "build/accuracy.h"
#include "build/layout.h"
#include "simd/isa.h"
#include "trace/bsdf.h"
#include "trace/kernel_list.h"
#include "trace/texture.h"

/* Ray/triangle algorithms. */
typedef enum lanes_tri_algo {
    LANES_TRI_MOLLER = 0,     /* Möller–Trumbore, two-sided, hit iff det != 0 */
    LANES_TRI_WATERTIGHT = 1, /* Woop, Benthin, Wald 2013, double fallback at 0 */
    LANES_TRI_ALGO_COUNT
} lanes_tri_algo;

/* How directions are inverted. */
typedef enum lanes_rcp_mode {
    LANES_RCP_EXACT = 0,  /* 1/d by division */
    LANES_RCP_FAST = 1,   /* hardware estimate plus one Newton step */
    LANES_RCP_MODE_COUNT
} lanes_rcp_mode;

/* rays_load_soa's flags per ray. */
enum { LANES_RAY_INVALID = 1, LANES_RAY_MAYBE_FAR = 2 };

/* 1 + 2 gamma(3) (Ize, "Robust BVH Ray Traversal", 2013): the slab exit
 * scaled by this is never below the exact exit, whatever the three
 * roundings of (plane - o) * (1/d) did. Without it a ray that passes exactly
 * through a box's edge or corner (aimed at a mesh vertex) can see entry >
 * exit by one rounding and lose the triangle there. */
#define LANES_ROBUST_SCALE 0x1.000006p+0f

/* What an accuracy mode (accuracy.h) switches on in the kernels. */
typedef struct lanes_precision {
    lanes_rcp_mode rcp;
    lanes_tri_algo algo;
    float exit_scale; /* box exits are multiplied by this: 1 or LANES_ROBUST_SCALE */
} lanes_precision;

static inline lanes_precision lanes_accuracy_precision(lanes_accuracy a)
{
    lanes_precision p = {LANES_RCP_EXACT, LANES_TRI_MOLLER, 1.0f};
    if (a == LANES_ACCURACY_FAST) p.rcp = LANES_RCP_FAST;
    if (a == LANES_ACCURACY_ROBUST) {
        p.algo = LANES_TRI_WATERTIGHT;
        p.exit_scale = LANES_ROBUST_SCALE;
    }
    return p;
}

/* A bound on a set of rays, for culling boxes and triangles that none of
 * them can hit. Two representations, both built from the same rays:
 *
 * - Intervals (Reshetov et al. 2005 corner rays; Boulos et al. 2006 interval
 *   arithmetic): per axis, the range of origins, of directions and of
 *   reciprocal directions. An axis whose directions change sign or touch 0
 *   has ia_axis_ok = 0 and takes no part in the slab-interval test.
 * - Planes (Reshetov 2007 vertex culling, Wu 2016 2.2.3): the dominant axis
 *   k (all directions share its sign), the near plane x_k = near at the
 *   smallest origin (largest, when directions point down k), and on each
 *   other axis a lower and an upper bounding plane
 *      x_a >= lo0[a] + lo_slope[a] * (x_k - near) * sign,  x_a <= hi0[a] + ...
 *   that hold for every point of every ray beyond the near plane.
 *   has_planes = 0 when no axis is shared by all directions.
 *
 * Every quantity is widened outward (outward rounding), so a cull is
 * conservative: no box or triangle that any of the rays hits is rejected. */
typedef struct lanes_frustum {
    bool valid;            /* false: some ray is invalid or too large; culls nothing */
    bool empty;            /* no active rays: culls everything */
    float tnear, tfar;     /* min tnear, max tfar of the active rays */
    float omin[3], omax[3];
    float dmin[3], dmax[3];
    float rmin[3], rmax[3];
    bool ia_axis_ok[3];
    bool has_planes;
    int k;                 /* dominant axis */
    float ksign;           /* +1 or -1: the sign of every d[k] */
    float near;            /* the near plane's coordinate on axis k */
    float lo0[3], lo_slope[3], hi0[3], hi_slope[3]; /* used for the two axes != k */
} lanes_frustum;

typedef enum lanes_cull_method {
    LANES_CULL_INTERVAL = 1, /* slab intervals for boxes, Boulos IA for triangles */
    LANES_CULL_PLANES = 2,   /* bounding planes (vertex culling) */
    LANES_CULL_BOTH = 3
} lanes_cull_method;

/* Lane accounting: how full the vectors were. */
typedef struct lanes_lane_stats {
    uint64_t vector_ops;   /* vector iterations of a kernel's main loop */
    uint64_t lane_slots;   /* vector_ops * lanes */
    uint64_t active_lanes; /* lanes that carried a real ray or primitive */
} lanes_lane_stats;

/* Adds the counters of b into a (per-thread counters summed at the end). */
static inline void lanes_lane_stats_add(lanes_lane_stats *a, const lanes_lane_stats *b)
{
    a->vector_ops += b->vector_ops;
    a->lane_slots += b->lane_slots;
    a->active_lanes += b->active_lanes;
}

/* What a traversal did, for the utilisation studies. */
typedef struct lanes_trace_stats {
    uint64_t rays;
    uint64_t nodes_visited;     /* interior node tests (one node, all its children) */
    uint64_t leaves_visited;
    uint64_t triangles_tested;
    lanes_lane_stats node_lanes; /* lanes of the box tests that held a real child */
    lanes_lane_stats leaf_lanes; /* lanes of the triangle tests that held a real triangle */
} lanes_trace_stats;

/* Adds the counters of b into a (per-thread counters summed at the end). */
static inline void lanes_trace_stats_add(lanes_trace_stats *a, const lanes_trace_stats *b)
{
    a->rays += b->rays;
    a->nodes_visited += b->nodes_visited;
    a->leaves_visited += b->leaves_visited;
    a->triangles_tested += b->triangles_tested;
    lanes_lane_stats_add(&a->node_lanes, &b->node_lanes);
    lanes_lane_stats_add(&a->leaf_lanes, &b->leaf_lanes);
}

struct lanes_bvh2;
struct lanes_wbvh;

/* Packet traversal (Wu 2016 ch. 3; Overbeck et al. 2008): a packet of up to
 * LANES_PACKET_MAX_RAYS rays traverses the BVH2 together, SIMD across its
 * rays. The rays are taken LANES_W at a time as fixed ray groups (rays
 * g*W .. g*W+W-1 of the packet: 2x2, 2x4 or 4x4 pixel tiles when the packet
 * builder lays primary rays out that way). */
#define LANES_PACKET_MAX_RAYS 1024

typedef enum lanes_packet_scheme {
    /* Partition traversal: at each node the groups with a live ray are moved
     * to the front of an index list, and only those go on. */
    LANES_PACKET_PARTITION = 0,
    /* Ranged (first/last active) traversal: the groups between the first
     * and the last one that hits go on, in their fixed order. */
    LANES_PACKET_RANGED = 1,
    LANES_PACKET_SCHEME_COUNT
} lanes_packet_scheme;

/* Options of one packet trace. */
typedef struct lanes_packet_options {
    lanes_packet_scheme scheme;
    lanes_accuracy accuracy; /* triangle test and box-exit widening; the rays are prepared by the caller */
    const lanes_frustum *frustum; /* the packet's frustum: nodes outside it are skipped; may be NULL */
    bool corner_test;   /* all four corner rays hit a node => all live rays do (before any elimination) */
    bool leaf_frustum;  /* rebuild a frustum from the live rays at each leaf and cull its triangles */
    bool occlusion;     /* any-hit: a ray stops at its first hit */
} lanes_packet_options;

/* Counts for the utilisation metrics. Box and triangle "ops" are the
 * SIMD ray-group tests; their lanes count the live rays (Wu Def. 4.2.1;
 * the packet utilisation of Def. 4.2.2 is active_lanes / lane_slots). */
typedef struct lanes_packet_stats {
    uint64_t packets, rays;
    uint64_t nodes_visited, leaves_visited; /* nodes reached with live rays */
    uint64_t node_live_rays, leaf_live_rays; /* sums, for the average live rays per visited node and leaf */
    uint64_t frustum_culled, corner_all_hit;
    uint64_t triangles_culled, triangles_tested;
    lanes_lane_stats box_ops, tri_ops;
} lanes_packet_stats;

/* a += b, field by field (per-thread counts summed). */
static inline void lanes_packet_stats_add(lanes_packet_stats *a, const lanes_packet_stats *b)
{
    a->packets += b->packets;
    a->rays += b->rays;
    a->nodes_visited += b->nodes_visited;
    a->leaves_visited += b->leaves_visited;
    a->node_live_rays += b->node_live_rays;
    a->leaf_live_rays += b->leaf_live_rays;
    a->frustum_culled += b->frustum_culled;
    a->corner_all_hit += b->corner_all_hit;
    a->triangles_culled += b->triangles_culled;
    a->triangles_tested += b->triangles_tested;
    lanes_lane_stats_add(&a->box_ops, &b->box_ops);
    lanes_lane_stats_add(&a->tri_ops, &b->tri_ops);
}

/* The kernels of one instruction set. Every entry is filled. */
typedef struct lanes_kernels {
    lanes_isa isa;
    int lanes;
    const char *name;
    /* The compiler's view when this set was built, checked by the tests:
     * bit 0 SSE4.1, 1 AVX, 2 AVX2, 3 FMA, 4 AVX-512F. */
    uint32_t compiled_features;

    /* Single-ray traversal reads a wide BVH of this many children. */
    int wide_width;

    /* The kernels, one member per row of kernel_list.h (which says what
     * each does). */
    LANES_KERNELS(LANES_KERNEL_MEMBER)
} lanes_kernels;

/* The kernels of a set that read a wide BVH, compiled for one node width
 * wider than the set's own (width 0: the set has none for that width). */
typedef struct lanes_wide_kernels {
    int width;
    LANES_KERNELS_WIDE_BVH(LANES_KERNEL_MEMBER)
} lanes_wide_kernels;

/* The table of the active set (lanes_isa_current()). */
const lanes_kernels *lanes_kernels_current(void);
/* The table of a given set, or NULL when it is not compiled in. Calling a
 * table the CPU cannot run is the caller's fault: check
 * lanes_isa_supported() first. */
const lanes_kernels *lanes_kernels_for(lanes_isa isa);
/* The table of a set for wide BVHs of node_width (4, 8 or 16) children:
 * the set's own when that is its wide_width; else the same table with
 * wide_width and the wide-BVH kernels (LANES_KERNELS_WIDE_BVH) of that
 * width. NULL when the set is not compiled in or has no kernels for the
 * width: a node is whole vectors of the set, so widths below its lane
 * count are not compiled (node widths: scalar and sse4 4, 8, 16; avx, avx2
 * and avx512vl8 8, 16; avx512emu and avx512 16). */
const lanes_kernels *lanes_kernels_for_width(lanes_isa isa, int node_width);

/* The rule every prepare applies: no NaN or infinite component in o or d,
 * d != 0, no NaN tnear or tfar. */
bool lanes_ray_valid(const lanes_ray *ray);
/* Scalar setup of one ray (reciprocal by division); returns false, and makes
 * the ray inactive, when it is invalid. */
bool lanes_ray_prepare(lanes_ray *ray);
/* The same with the reciprocal of an accuracy mode: LANES_RCP_FAST takes the
 * SSE estimate plus one Newton step, as the kernels' fast mode does. */
bool lanes_ray_prepare_rcp(lanes_ray *ray, lanes_rcp_mode mode);

#endif
