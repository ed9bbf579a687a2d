/* Single-ray traversal of a wide BVH (lanes_wbvh), shared by the kernels
 * that walk one: traverse_kernels.c (one ray at a time) and
 * hybrid_kernels.c (packets that hand their last rays to it). Included only
 * by per-ISA files; everything is static inline (see simd/simd.h). */
#ifndef LANES_TRACE_WIDE_CORE_H
#define LANES_TRACE_WIDE_CORE_H

#include "build/bvh.h"
#include "trace/kernels/triangle_core.h"

#define WIDE_WIDTH LANES_WIDE_WIDTH

/* BVH depth is bounded by the builder (64 levels), so a stack of
 * 64 * (width - 1) + 1 entries cannot overflow. */
#define STACK_SIZE (64 * WIDE_WIDTH)

/* A wide BVH's child: its ref (lanes_wbvh) and entry distance. */
typedef struct {
    uint32_t ref;
    float t;
} wide_entry;

/* How a node's slab distances are computed:
 * - SLAB_FMA: plane * (1/d) - o * (1/d), one FMA on the ray's precomputed
 *   o * (1/d) (fast mode). On sets without FMA it is a
 *   multiply and a subtraction, two roundings.
 * - SLAB_EXACT: (plane - o) * (1/d), for rays whose o * (1/d) overflows
 *   (a huge origin over a tiny direction component), where the FMA form
 *   would give -inf - -inf.
 * - SLAB_ROBUST: (plane - o) * (1/d) with the exit widened by
 *   LANES_ROBUST_SCALE, so no box a ray really touches is skipped (robust
 *   mode). The other two may lose a box the ray grazes by a rounding.
 * Near planes are picked by the ray's octant; NaN slab distances (a zero
 * direction component in a box's plane) are ignored by operand order. */
enum { SLAB_FMA, SLAB_EXACT, SLAB_ROBUST };

typedef struct {
    int near[3], far[3];
    vfloat o[3], rd[3], ord[3], tnear, exit_scale;
} node_ray;

/* The slab form of an accuracy mode: every ray's but a fast-mode ray whose
 * o * (1/d) overflows. */
static inline int mode_slab(lanes_accuracy accuracy, float exit_scale)
{
    return exit_scale != 1.0f ? SLAB_ROBUST : accuracy == LANES_ACCURACY_FAST ? SLAB_FMA : SLAB_EXACT;
}

/* The slab form for ray r (see above). */
static inline int ray_slab(const lanes_ray *r, lanes_accuracy accuracy, float exit_scale)
{
    const int slab = mode_slab(accuracy, exit_scale);
    if (slab != SLAB_FMA) return slab;
    for (int a = 0; a < 3; a++)
        if (!(fabsf(r->o[a] * r->rd[a]) <= FLT_MAX)) return SLAB_EXACT;
    return SLAB_FMA;
}

/* The direction octant of a ray: the signs of its 1/d, one bit per axis,
 * which pick a box's near and far planes. */
static inline unsigned ray_octant(const lanes_ray *r)
{
    return (unsigned)(r->rd[0] < 0.0f) | (unsigned)(r->rd[1] < 0.0f) << 1 | (unsigned)(r->rd[2] < 0.0f) << 2;
}

/* Fills *n in place and returns the ray's slab form: a returned copy of
 * the struct (11 vectors) cost the avx512emu set, whose vectors are pairs
 * of ymm registers, about 5% of a ray's instructions (callgrind). */
LANES_BODY int node_ray_init(node_ray *n, const lanes_ray *r, lanes_accuracy accuracy, float exit_scale)
{
    for (int a = 0; a < 3; a++) {
        n->near[a] = r->rd[a] < 0.0f ? a + 3 : a;
        n->far[a] = r->rd[a] < 0.0f ? a : a + 3;
        n->o[a] = vf_set1(r->o[a]);
        n->rd[a] = vf_set1(r->rd[a]);
        n->ord[a] = vf_set1(r->o[a] * r->rd[a]);
    }
    n->tnear = vf_set1(r->tnear);
    n->exit_scale = vf_set1(exit_scale);
    return ray_slab(r, accuracy, exit_scale);
}

LANES_BODY vfloat slab_t(int slab, vfloat plane, const node_ray *r, int a)
{
    if (slab == SLAB_FMA) return vf_fmsub(plane, r->rd[a], r->ord[a]);
    return vf_mul(vf_sub(plane, r->o[a]), r->rd[a]);
}

/* A node's child boxes as one ray octant sees them: per vector of LANES_W
 * children, the near and far plane of each axis. */
enum { NODE_VECTORS = WIDE_WIDTH / LANES_W };
typedef struct {
    vfloat near[NODE_VECTORS][3], far[NODE_VECTORS][3];
} node_planes;

LANES_BODY void load_planes(const float *node, const int near[3], const int far[3], node_planes *p)
{
    for (int c = 0; c < NODE_VECTORS; c++)
        for (int a = 0; a < 3; a++) {
            p->near[c][a] = vf_load(node + near[a] * WIDE_WIDTH + c * LANES_W);
            p->far[c][a] = vf_load(node + far[a] * WIDE_WIDTH + c * LANES_W);
        }
}

/* Lane j set: the ray enters child c * LANES_W + j before tfar; *tin its
 * entry distances. */
LANES_BODY vmask planes_test(const node_planes *p, const node_ray *r, int slab, vfloat tfar, int c, vfloat *tin)
{
    vfloat in = r->tnear, out = tfar;
    for (int a = 0; a < 3; a++) {
        in = vf_max(slab_t(slab, p->near[c][a], r, a), in);
        out = vf_min(slab_t(slab, p->far[c][a], r, a), out);
    }
    if (slab == SLAB_ROBUST) out = vf_mul(out, r->exit_scale);
    *tin = in;
    return vf_le(in, out);
}

/* Bit j set: the ray enters child j before tfar; tentry[j] its entry. */
LANES_BODY uint32_t planes_hits(const node_planes *p, const node_ray *r, int slab, float tfar, float *tentry)
{
    uint32_t bits = 0;
    vfloat tf = vf_set1(tfar);
    for (int c = 0; c < NODE_VECTORS; c++) {
        vfloat tin;
        bits |= vm_bits(planes_test(p, r, slab, tf, c, &tin)) << (c * LANES_W);
        vf_storeu(tentry + c * LANES_W, tin);
    }
    return bits;
}

LANES_BODY uint32_t node_hits(const float *node, const node_ray *r, int slab, float tfar, float *tentry)
{
    node_planes p;
    load_planes(node, r->near, r->far, &p);
    return planes_hits(&p, r, slab, tfar, tentry);
}

enum {
    NODE_BYTES = (WIDE_WIDTH * 28 + 63) / 64 * 64,
    BLOCK_BYTES = (WIDE_WIDTH * 40 + 31) / 32 * 32,
    ID_BLOCK_BYTES = (WIDE_WIDTH * 4 + 31) / 32 * 32
};

/* Real triangles among lanes k .. k+LANES_W-1 of a block (padding comes
 * last, lane 0 is always a triangle, so the leaf loops below read prim[]
 * only past it: sets as wide as the block never touch that cache line
 * before a hit), for the counters. */
static inline vmask block_live(const uint32_t *prim, int k)
{
    int n = 0;
    while (n < LANES_W && prim[k + n] != LANES_NO_HIT) n++;
    return vm_first_n((size_t)n);
}

/* The lane of the nearest hit in h, if it beats the best so far (strictly:
 * ties keep the earlier triangle); -1 otherwise. */
LANES_BODY int nearer_lane(const tri_result *h, bool found, float tfar)
{
    if (vm_none(h->hit)) return -1;
    float tmin = vf_reduce_min(vf_select(h->hit, h->t, vf_set1(INFINITY)));
    if (found && !(tmin < tfar)) return -1;
    return __builtin_ctz(vm_bits(vm_and(h->hit, vf_eq(h->t, vf_set1(tmin)))));
}

LANES_BODY void record_hit(const tri_result *h, int lane, uint32_t prim, float *tfar, lanes_hit *hit)
{
    hit->t = vf_lane(h->t, lane);
    hit->u = vf_lane(h->u, lane);
    hit->v = vf_lane(h->v, lane);
    hit->prim = prim;
    *tfar = hit->t;
}

/* A leaf's first block, and the bytes from one to the next: the tree's
 * own vertices (BLOCK_BYTES) or triangle ids of the caller's arrays
 * (lanes_wbvh_share). */
static inline const unsigned char *leaf_blocks(const lanes_wbvh *wb, uint32_t ref)
{
    return wb->blocks + (size_t)lanes_wref_block(ref) * (wb->shared_verts ? ID_BLOCK_BYTES : BLOCK_BYTES);
}

static inline const uint32_t *block_prims(const lanes_wbvh *wb, const unsigned char *blk)
{
    return (const uint32_t *)(const void *)(wb->shared_verts ? blk : blk + 36 * WIDE_WIDTH);
}

/* Lanes k .. k+LANES_W-1 of a leaf block, in either layout. */
LANES_BODY tri_result block_test(const lanes_wbvh *wb, lanes_tri_algo algo, const wide_setup *w,
                                 const unsigned char *blk, int k, vfloat tfar, bool want_uv)
{
    if (wb->shared_verts)
        return ray_vs_shared(algo, w, wb->shared_verts, wb->shared_indices,
                             (const uint32_t *)(const void *)blk, (size_t)k, tfar, want_uv);
    return ray_vs_block(algo, w, (const float *)(const void *)blk, (size_t)k, tfar, want_uv);
}

/* Closest hit in a leaf's blocks with t <= *tfar; updates *tfar and *hit.
 * Ties keep the earlier triangle. */
LANES_BODY bool leaf_closest(const lanes_wbvh *wb, lanes_tri_algo algo, const wide_setup *w, uint32_t ref,
                             float *tfar, lanes_hit *hit, lanes_trace_stats *stats)
{
    bool found = false;
    const unsigned char *blk = leaf_blocks(wb, ref);
    const size_t stride = wb->shared_verts ? ID_BLOCK_BYTES : BLOCK_BYTES;
    for (uint32_t b = 0, nblocks = lanes_wref_blocks(ref); b < nblocks; b++, blk += stride) {
        const uint32_t *prim = block_prims(wb, blk);
        for (int k = 0; k < WIDE_WIDTH && (k == 0 || prim[k] != LANES_NO_HIT); k += LANES_W) {
            tri_result h = block_test(wb, algo, w, blk, k, vf_set1(*tfar), true);
            if (stats) {
                vmask live = block_live(prim, k);
                stats->triangles_tested += (uint64_t)vm_popcount(live);
                LANES_COUNT(&stats->leaf_lanes, live);
            }
            int lane = nearer_lane(&h, found, *tfar);
            if (lane < 0) continue;
            record_hit(&h, lane, prim[k + lane], tfar, hit);
            found = true;
        }
    }
    return found;
}

LANES_BODY bool leaf_any(const lanes_wbvh *wb, lanes_tri_algo algo, const wide_setup *w, uint32_t ref,
                         lanes_trace_stats *stats)
{
    const unsigned char *blk = leaf_blocks(wb, ref);
    const size_t stride = wb->shared_verts ? ID_BLOCK_BYTES : BLOCK_BYTES;
    for (uint32_t b = 0, nblocks = lanes_wref_blocks(ref); b < nblocks; b++, blk += stride) {
        const uint32_t *prim = block_prims(wb, blk);
        for (int k = 0; k < WIDE_WIDTH && (k == 0 || prim[k] != LANES_NO_HIT); k += LANES_W) {
            tri_result h = block_test(wb, algo, w, blk, k, w->tfar, false);
            if (stats) {
                vmask live = block_live(prim, k);
                stats->triangles_tested += (uint64_t)vm_popcount(live);
                LANES_COUNT(&stats->leaf_lanes, live);
            }
            if (vm_any(h.hit)) return true;
        }
    }
    return false;
}

static inline void count_node(lanes_trace_stats *stats, const uint32_t *ref)
{
    int used = 0;
    for (int j = 0; j < WIDE_WIDTH; j++) used += ref[j] != LANES_WBVH_EMPTY;
    stats->nodes_visited++;
    stats->node_lanes.vector_ops += (WIDE_WIDTH + LANES_W - 1) / LANES_W;
    stats->node_lanes.lane_slots += WIDE_WIDTH;
    stats->node_lanes.active_lanes += (uint64_t)used;
}

/* The memory a child will be read from, requested while the nearer
 * children are traversed. */
static inline void prefetch_child(const lanes_wbvh *wb, uint32_t ref)
{
    const unsigned char *p;
    int lines;
    if (lanes_wref_is_leaf(ref)) {
        p = leaf_blocks(wb, ref);
        lines = ((wb->shared_verts ? ID_BLOCK_BYTES : BLOCK_BYTES) + 63) / 64;
    } else {
        p = wb->nodes + (size_t)ref * NODE_BYTES;
        lines = NODE_BYTES / 64;
    }
    for (int l = 0; l < lines; l++) __builtin_prefetch(p + 64 * l);
}

/* Inserts c into base[0 .. n), kept in decreasing entry distance. A
 * stable network of neighbour exchanges for three and four children, free
 * of data-dependent branches, measured the same (1.00x, geometric mean over
 * dragon, sponza-bunny and 20-bunnies, every ray kind and scheme, avx2, Zen
 * 4, clang 14, alternating runs; the other rows 0.93-1.10, inside the
 * noise: the shadow rows, whose code it left alone, moved 0.88-1.12), so
 * this simpler loop stays. */
static inline int insert_nearest_last(wide_entry *base, int n, wide_entry c)
{
    int k = n;
    while (k > 0 && base[k - 1].t < c.t) {
        base[k] = base[k - 1];
        k--;
    }
    base[k] = c;
    return n + 1;
}

/* Walks the subtree of start (the root, or where a packet left off) for
 * one ray whose best distance so far is *tfar; returns whether it found a
 * hit there (written to *hit, *tfar shrunk to it). any == true stops at the
 * first hit. */
LANES_BODY bool wide_walk(const lanes_wbvh *wb, lanes_tri_algo algo, int slab, const node_ray *nr,
                          const wide_setup *w, wide_entry start, float *tfar_io, bool any,
                          lanes_hit *hit, lanes_trace_stats *stats)
{
    const float exit_scale = slab == SLAB_ROBUST ? LANES_ROBUST_SCALE : 1.0f;
    wide_entry stack[STACK_SIZE];
    float tentry[WIDE_WIDTH];
    float tfar = *tfar_io;
    bool found = false;
    int sp = 0;
    wide_entry e = start;
    for (;;) {
        if (!(e.t > tfar * exit_scale)) {
            if (lanes_wref_is_leaf(e.ref)) {
                if (stats) stats->leaves_visited++;
                if (any) {
                    if (leaf_any(wb, algo, w, e.ref, stats)) return true;
                } else {
                    found |= leaf_closest(wb, algo, w, e.ref, &tfar, hit, stats);
                }
            } else {
                const float *node = (const float *)(const void *)(wb->nodes + (size_t)e.ref * NODE_BYTES);
                const uint32_t *ref = (const uint32_t *)(const void *)(node + 6 * WIDE_WIDTH);
                uint32_t bits = node_hits(node, nr, slab, tfar, tentry);
                if (stats) count_node(stats, ref);
                if (bits != 0) {
                    int j = __builtin_ctz(bits);
                    bits &= bits - 1;
                    wide_entry c0 = {ref[j], tentry[j]};
                    /* One hit child: straight on to it, without the stack,
                     * the common case below the top levels. */
                    if (bits == 0) {
                        e = c0;
                        continue;
                    }
                    j = __builtin_ctz(bits);
                    bits &= bits - 1;
                    wide_entry c1 = {ref[j], tentry[j]};
                    if (bits == 0) {
                        /* Two: the nearer next, the farther pushed. */
                        bool swap = c1.t < c0.t;
                        e = swap ? c1 : c0;
                        wide_entry far = swap ? c0 : c1;
                        prefetch_child(wb, far.ref);
                        stack[sp++] = far;
                        continue;
                    }
                    /* More: pushed farthest first by insertion sort (at most
                     * WIDE_WIDTH entries), the nearest taken off again. An
                     * occlusion query wants any hit, not the nearest: its
                     * children go on unsorted (shadow rays 8-10% faster on
                     * dragon and sponza-bunny than sorted). */
                    wide_entry *base = stack + sp;
                    bool c1_farther = !any && c0.t < c1.t;
                    base[0] = c1_farther ? c1 : c0;
                    base[1] = c1_farther ? c0 : c1;
                    int n = 2;
                    while (bits) {
                        j = __builtin_ctz(bits);
                        bits &= bits - 1;
                        wide_entry c = {ref[j], tentry[j]};
                        if (any)
                            base[n++] = c;
                        else
                            n = insert_nearest_last(base, n, c);
                    }
                    for (int k = 0; k < n - 1; k++) prefetch_child(wb, base[k].ref);
                    sp += n - 1;
                    e = base[n - 1];
                    continue;
                }
            }
        }
        if (sp == 0) break;
        e = stack[--sp];
    }
    *tfar_io = tfar;
    return found;
}

/* wide_walk with its slab form a constant in each copy. */
LANES_BODY bool wide_walk_from(const lanes_wbvh *wb, lanes_tri_algo algo, int slab, const node_ray *nr,
                               const wide_setup *w, wide_entry start, float *tfar, bool any,
                               lanes_hit *hit, lanes_trace_stats *stats)
{
    if (slab == SLAB_FMA) return wide_walk(wb, algo, SLAB_FMA, nr, w, start, tfar, any, hit, stats);
    if (slab == SLAB_ROBUST) return wide_walk(wb, algo, SLAB_ROBUST, nr, w, start, tfar, any, hit, stats);
    return wide_walk(wb, algo, SLAB_EXACT, nr, w, start, tfar, any, hit, stats);
}

/* Both traversals of one ray from the root: set-up, and the slab form chosen once. */
LANES_BODY bool wide_ray(const lanes_wbvh *wb, lanes_accuracy accuracy, const lanes_ray *ray, bool any,
                         lanes_hit *hit, lanes_trace_stats *stats)
{
    const lanes_precision prec = lanes_accuracy_precision(accuracy);
    if (!(ray->tnear <= ray->tfar)) return false;
    node_ray nr;
    const int slab = node_ray_init(&nr, ray, accuracy, prec.exit_scale);
    wide_setup w;
    wide_setup_init(&w, prec.algo, ray, NULL);
    float tfar = ray->tfar;
    return wide_walk_from(wb, prec.algo, slab, &nr, &w, (wide_entry){0, ray->tnear}, &tfar, any, hit, stats);
}

#endif
