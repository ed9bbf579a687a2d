/* Single-ray BVH traversal, written once and compiled per instruction set:
 * - wide: one ray against all children of a wide node at once (Bikker's
 *   single-ray MBVH baseline; Dammertz et al., Wald et al. 2008), children
 *   visited nearest first, leaf triangles SIMD across the leaf;
 * - bvh2: the binary BVH, two boxes at a time, the thesis' "single" scheme.
 * Both answer closest-hit and any-hit (occlusion) queries. */
#include "trace/kernels/kernel_decls.h"
#include "trace/kernels/wide_core.h"

typedef struct {
    uint32_t ref;   /* node index, or first triangle of a leaf */
    uint32_t count; /* 0: interior node; > 0: leaf of that many triangles */
    float t;        /* entry distance: skip when farther than the best hit */
} stack_entry;


/* The BVH2's leaves: triangles [first, first+count) of its SoA arrays, in
 * leaf order. Same conventions as the blocks above. */
LANES_BODY bool soa_leaf_closest(lanes_tri_algo algo, const wide_setup *w, const lanes_bvh2 *b,
                                 uint32_t first, uint32_t count, float *tfar, lanes_hit *hit,
                                 lanes_trace_stats *stats)
{
    bool found = false;
    for (uint32_t k = 0; k < count; k += LANES_W) {
        vmask live = vm_first_n(count - k);
        tri_result h = ray_vs_tris(algo, w, first + k, vf_set1(*tfar), live, true);
        if (stats) {
            stats->triangles_tested += (uint64_t)vm_popcount(live);
            LANES_COUNT(&stats->leaf_lanes, live);
        }
        int lane = nearer_lane(&h, found, *tfar);
        if (lane < 0) continue;
        record_hit(&h, lane, b->prim_index[first + k + (uint32_t)lane], tfar, hit);
        found = true;
    }
    return found;
}

LANES_BODY bool soa_leaf_any(lanes_tri_algo algo, const wide_setup *w, uint32_t first, uint32_t count,
                             lanes_trace_stats *stats)
{
    for (uint32_t k = 0; k < count; k += LANES_W) {
        vmask live = vm_first_n(count - k);
        tri_result h = ray_vs_tris(algo, w, first + k, w->tfar, live, false);
        if (stats) {
            stats->triangles_tested += (uint64_t)vm_popcount(live);
            LANES_COUNT(&stats->leaf_lanes, live);
        }
        if (vm_any(h.hit)) return true;
    }
    return false;
}

/* Slab test of one ray against one box, scalar, same conventions. */
static inline bool box_hit1(const lanes_bvh2_node *nd, const lanes_ray *r, float tfar,
                            float exit_scale, float *t)
{
    float tin = r->tnear, tout = tfar;
    for (int a = 0; a < 3; a++) {
        float t1 = (nd->min[a] - r->o[a]) * r->rd[a];
        float t2 = (nd->max[a] - r->o[a]) * r->rd[a];
        float tn = r->rd[a] < 0.0f ? t2 : t1, tf = r->rd[a] < 0.0f ? t1 : t2;
        tin = tn > tin ? tn : tin;
        tout = tf < tout ? tf : tout;
    }
    *t = tin;
    return tin <= tout * exit_scale;
}

LANES_BODY bool bvh2_walk(const lanes_bvh2 *b, lanes_accuracy accuracy, const lanes_ray *ray,
                          bool any, lanes_hit *hit, lanes_trace_stats *stats)
{
    const lanes_precision prec = lanes_accuracy_precision(accuracy);
    const lanes_tri_algo algo = prec.algo;
    stack_entry stack[64 * 2];
    float tfar = ray->tfar;
    bool found = false;
    if (!(ray->tnear <= ray->tfar) || b->node_count == 0) return false;
    wide_setup w;
    wide_setup_init(&w, algo, ray, &b->tris);
    int sp = 0;
    float troot;
    if (!box_hit1(&b->nodes[0], ray, tfar, prec.exit_scale, &troot)) return false;
    stack[sp++] = (stack_entry){0, 0, troot};
    while (sp > 0) {
        stack_entry e = stack[--sp];
        if (e.t > tfar * prec.exit_scale) continue;
        const lanes_bvh2_node *nd = &b->nodes[e.ref];
        if (nd->count > 0) {
            if (stats) stats->leaves_visited++;
            if (any) {
                if (soa_leaf_any(algo, &w, nd->first, nd->count, stats)) return true;
            } else {
                found |= soa_leaf_closest(algo, &w, b, nd->first, nd->count, &tfar, hit, stats);
            }
            continue;
        }
        if (stats) {
            stats->nodes_visited++;
            stats->node_lanes.vector_ops += 2;
            stats->node_lanes.lane_slots += 2;
            stats->node_lanes.active_lanes += 2;
        }
        float t0, t1;
        bool h0 = box_hit1(&b->nodes[nd->first], ray, tfar, prec.exit_scale, &t0);
        bool h1 = box_hit1(&b->nodes[nd->first + 1], ray, tfar, prec.exit_scale, &t1);
        if (h0 && h1) {
            bool first_near = t0 <= t1;
            stack[sp++] = (stack_entry){nd->first + (first_near ? 1u : 0u), 0, first_near ? t1 : t0};
            stack[sp++] = (stack_entry){nd->first + (first_near ? 0u : 1u), 0, first_near ? t0 : t1};
        } else if (h0) {
            stack[sp++] = (stack_entry){nd->first, 0, t0};
        } else if (h1) {
            stack[sp++] = (stack_entry){nd->first + 1, 0, t1};
        }
    }
    return found;
}

static inline lanes_hit no_hit(void) { return (lanes_hit){INFINITY, 0.0f, 0.0f, LANES_NO_HIT}; }

LANES_BODY void trace_wide_body(const lanes_wbvh *wb, lanes_accuracy accuracy, const lanes_ray *rays,
                                size_t n, lanes_hit *hits, lanes_trace_stats *stats)
{
    for (size_t i = 0; i < n; i++) {
        hits[i] = no_hit();
        wide_ray(wb, accuracy, &rays[i], false, &hits[i], stats);
    }
    if (stats) stats->rays += n;
}

LANES_BODY void occluded_wide_body(const lanes_wbvh *wb, lanes_accuracy accuracy, const lanes_ray *rays,
                                   size_t n, uint8_t *occluded, lanes_trace_stats *stats)
{
    for (size_t i = 0; i < n; i++) occluded[i] = wide_ray(wb, accuracy, &rays[i], true, NULL, stats);
    if (stats) stats->rays += n;
}

LANES_BODY void trace_bvh2_body(const lanes_bvh2 *b, lanes_accuracy accuracy, const lanes_ray *rays,
                                size_t n, lanes_hit *hits, lanes_trace_stats *stats)
{
    for (size_t i = 0; i < n; i++) {
        hits[i] = no_hit();
        bvh2_walk(b, accuracy, &rays[i], false, &hits[i], stats);
    }
    if (stats) stats->rays += n;
}

LANES_BODY void occluded_bvh2_body(const lanes_bvh2 *b, lanes_accuracy accuracy, const lanes_ray *rays,
                                   size_t n, uint8_t *occluded, lanes_trace_stats *stats)
{
    for (size_t i = 0; i < n; i++) occluded[i] = bvh2_walk(b, accuracy, &rays[i], true, NULL, stats);
    if (stats) stats->rays += n;
}

/* The entry points: each body instantiated with and without counting.
 * The BVH2 reads no wide node: one copy per set. */
LANES_KERNELS_TRAVERSE_WIDE(LANES_KERNEL_ENTRY)
#ifndef LANES_WIDE_TAG
LANES_KERNELS_TRAVERSE_BVH2(LANES_KERNEL_ENTRY)
#endif
