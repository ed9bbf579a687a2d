/* The hot kernels' data layouts and the table through which every caller
 * reaches them. The kernels themselves are written once (trace/kernels/<family>_kernels.c)
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
 * - Hit masks are bit arrays: bit i of word i/32 is ray (or primitive) i.
 * - Where a kernel writes per-hit values (t, u, v), it writes them only for
 *   hits; the caller's values for misses are left untouched.
 * - Arrays are 64-byte aligned and padded (lanes_*_alloc): past the count
 *   they hold at least LANES_MAX_W more elements, so a full-width load that
 *   starts at any element below the count stays inside the allocation.
 *   Results past the count are never written.
 * - stats, when not NULL, accumulates lane accounting. With NULL the kernel
 *   runs a copy of its body with the counting compiled out.
 */
#ifndef LANES_TRACE_KERNELS_H
#define LANES_TRACE_KERNELS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "simd/isa.h"
#include "trace/accuracy.h"
#include "trace/kernel_list.h"

#define LANES_MAX_W 16
#define LANES_ALIGN 64

/* Rays in structure-of-arrays form. */
typedef struct lanes_rays {
    float *ox, *oy, *oz;
    float *dx, *dy, *dz;
    float *rdx, *rdy, *rdz; /* 1/d, filled by lanes_rays_prepare */
    float *tnear, *tfar;
    size_t count;     /* rays in use */
    size_t capacity;  /* allocated elements per array */
} lanes_rays;

/* One ray, with its reciprocal direction (see lanes_ray_prepare). */
typedef struct lanes_ray {
    float o[3], d[3], rd[3];
    float tnear, tfar;
} lanes_ray;

typedef struct lanes_box {
    float min[3], max[3];
} lanes_box;

/* Boxes in structure-of-arrays form, the layout of a wide BVH node. */
typedef struct lanes_boxes {
    float *minx, *miny, *minz, *maxx, *maxy, *maxz;
    size_t count, capacity;
} lanes_boxes;

typedef struct lanes_triangle {
    float v0[3], v1[3], v2[3];
} lanes_triangle;

/* Triangles in structure-of-arrays form (the wide kernels load them
 * unaligned, so a view may start at any element). Vertices, not edges, are stored:
 * the watertight test needs each shared vertex transformed identically. */
typedef struct lanes_triangles {
    float *v0x, *v0y, *v0z, *v1x, *v1y, *v1z, *v2x, *v2y, *v2z;
    size_t count, capacity;
} lanes_triangles;

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

/* Results of the per-element triangle kernels. */
typedef struct lanes_tri_hits {
    float *t, *u, *v; /* u, v: barycentric weights of v1 and v2 */
} lanes_tri_hits;

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

/* Result of a closest-hit query. prim is the scene triangle index, or
 * LANES_NO_HIT; u, v are the barycentric weights of v1 and v2. */
#define LANES_NO_HIT 0xffffffffu
typedef struct lanes_hit {
    float t, u, v;
    uint32_t prim;
} lanes_hit;

/* What a traversal did, for the utilisation studies. */
typedef struct lanes_trace_stats {
    uint64_t rays;
    uint64_t nodes_visited;     /* interior node tests (one node, all its children) */
    uint64_t leaves_visited;
    uint64_t triangles_tested;
    lanes_lane_stats node_lanes; /* lanes of the box tests that held a real child */
    lanes_lane_stats leaf_lanes; /* lanes of the triangle tests that held a real triangle */
} lanes_trace_stats;

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

/* The table of the active set (lanes_isa_current()). */
const lanes_kernels *lanes_kernels_current(void);
/* The table of a given set, or NULL when it is not compiled in. Calling a
 * table the CPU cannot run is the caller's fault: check
 * lanes_isa_supported() first. */
const lanes_kernels *lanes_kernels_for(lanes_isa isa);

/* The rule every prepare applies: no NaN or infinite component in o or d,
 * d != 0, no NaN tnear or tfar. */
bool lanes_ray_valid(const lanes_ray *ray);
/* Scalar setup of one ray (reciprocal by division); returns false, and makes
 * the ray inactive, when it is invalid. */
bool lanes_ray_prepare(lanes_ray *ray);
/* The same with the reciprocal of an accuracy mode: LANES_RCP_FAST takes the
 * SSE estimate plus one Newton step, as the kernels' fast mode does. */
bool lanes_ray_prepare_rcp(lanes_ray *ray, lanes_rcp_mode mode);

/* Allocation of padded, aligned SoA arrays; counts are checked against
 * overflow. Return false on failure (absurd size, out of memory). */
bool lanes_rays_alloc(lanes_rays *rays, size_t count);
void lanes_rays_free(lanes_rays *rays);
bool lanes_boxes_alloc(lanes_boxes *boxes, size_t count);
void lanes_boxes_free(lanes_boxes *boxes);
bool lanes_triangles_alloc(lanes_triangles *tris, size_t count);
void lanes_triangles_free(lanes_triangles *tris);
bool lanes_tri_hits_alloc(lanes_tri_hits *hits, size_t count);
void lanes_tri_hits_free(lanes_tri_hits *hits);

/* Views of elements [first, first + count) of SoA arrays, sharing their
 * storage: a packet of a larger ray set, a BVH leaf's triangles. The
 * allocation's slack covers full-width loads from any start (see above). */
static inline lanes_rays lanes_rays_view(const lanes_rays *r, size_t first, size_t count)
{
    lanes_rays v = *r;
    v.ox += first, v.oy += first, v.oz += first;
    v.dx += first, v.dy += first, v.dz += first;
    v.rdx += first, v.rdy += first, v.rdz += first;
    v.tnear += first, v.tfar += first;
    v.count = count;
    v.capacity = r->capacity - first;
    return v;
}

static inline lanes_triangles lanes_triangles_view(const lanes_triangles *t, size_t first, size_t count)
{
    lanes_triangles v = *t;
    v.v0x += first, v.v0y += first, v.v0z += first;
    v.v1x += first, v.v1y += first, v.v1z += first;
    v.v2x += first, v.v2y += first, v.v2z += first;
    v.count = count;
    v.capacity = t->capacity - first;
    return v;
}

/* Bit-array helpers. */
static inline size_t lanes_mask_words(size_t n) { return (n + 31) / 32; }
static inline bool lanes_mask_get(const uint32_t *mask, size_t i)
{
    return (mask[i / 32] >> (i % 32)) & 1u;
}

#endif
