/* Single-ray BVH traversal, written once and compiled per instruction set:
 * - wide: one ray against all children of a wide node at once (Bikker's
 *   single-ray MBVH baseline; Dammertz et al., Wald et al. 2008), children
 *   visited nearest first, leaf triangles SIMD across the leaf;
 * - bvh2: the binary BVH, two boxes at a time, the thesis' "single" scheme.
 * Both answer closest-hit and any-hit (occlusion) queries. */
#include "build/bvh.h"
#include "trace/kernels/kernel_decls.h"
#include "trace/kernels/triangle_core.h"

#define WIDE_WIDTH LANES_WIDE_WIDTH

/* BVH depth is bounded by the builder (64 levels), so a stack of
 * 64 * (width - 1) + 1 entries cannot overflow. */
#define STACK_SIZE (64 * WIDE_WIDTH)

typedef struct {
    uint32_t ref;   /* node index, or first triangle of a leaf */
    uint32_t count; /* 0: interior node; > 0: leaf of that many triangles */
    float t;        /* entry distance: skip when farther than the best hit */
} stack_entry;

/* Entry of one ray into the children j .. j+LANES_W-1 of a wide node (slab
 * test as in box_kernels.c: near planes by the ray's octant, NaN slab
 * distances ignored by operand order). In robust mode the exit is widened
 * by LANES_ROBUST_SCALE so no box a ray really touches is skipped; the
 * other modes take exit_scale = 1 and may lose a box by one rounding. */
typedef struct {
    int near[3], far[3];
    vfloat o[3], rd[3], tnear, exit_scale;
} node_ray;

static inline node_ray node_ray_setup(const lanes_ray *r, float exit_scale)
{
    node_ray n;
    for (int a = 0; a < 3; a++) {
        n.near[a] = r->rd[a] < 0.0f ? a + 3 : a;
        n.far[a] = r->rd[a] < 0.0f ? a : a + 3;
        n.o[a] = vf_set1(r->o[a]);
        n.rd[a] = vf_set1(r->rd[a]);
    }
    n.tnear = vf_set1(r->tnear);
    n.exit_scale = vf_set1(exit_scale);
    return n;
}

LANES_BODY uint32_t node_hits(const float *node, const node_ray *r, float tfar, float *tentry)
{
    uint32_t bits = 0;
    vfloat tf = vf_set1(tfar);
    for (int j = 0; j < WIDE_WIDTH; j += LANES_W) {
        vfloat tin = r->tnear, tout = tf;
        for (int a = 0; a < 3; a++) {
            tin = vf_max(vf_mul(vf_sub(vf_load(node + r->near[a] * WIDE_WIDTH + j), r->o[a]), r->rd[a]), tin);
            tout = vf_min(vf_mul(vf_sub(vf_load(node + r->far[a] * WIDE_WIDTH + j), r->o[a]), r->rd[a]), tout);
        }
        vmask m = vf_le(tin, vf_mul(tout, r->exit_scale));
        vf_storeu(tentry + j, tin);
        bits |= vm_bits(m) << j;
    }
    return bits;
}

/* Closest hit among a leaf's triangles [first, first+count) with t <= *tfar;
 * updates *tfar and *hit. Ties keep the earlier triangle. */
LANES_BODY bool leaf_closest(lanes_tri_algo algo, const wide_setup *w, const lanes_bvh2 *b,
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
        if (vm_none(h.hit)) continue;
        float tmin = vf_reduce_min(vf_select(h.hit, h.t, vf_set1(INFINITY)));
        if (found && !(tmin < *tfar)) continue;
        int lane = __builtin_ctz(vm_bits(vm_and(h.hit, vf_eq(h.t, vf_set1(tmin)))));
        hit->t = tmin;
        hit->u = vf_lane(h.u, lane);
        hit->v = vf_lane(h.v, lane);
        hit->prim = b->prim_index[first + k + (uint32_t)lane];
        *tfar = tmin;
        found = true;
    }
    return found;
}

LANES_BODY bool leaf_any(lanes_tri_algo algo, const wide_setup *w, uint32_t first, uint32_t count,
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

static inline void count_node(lanes_trace_stats *stats, const lanes_wbvh *wb, uint32_t node)
{
    int used = 0;
    for (int j = 0; j < WIDE_WIDTH; j++) used += wb->child[(size_t)node * WIDE_WIDTH + j] != LANES_WBVH_EMPTY;
    stats->nodes_visited++;
    stats->node_lanes.vector_ops += (WIDE_WIDTH + LANES_W - 1) / LANES_W;
    stats->node_lanes.lane_slots += WIDE_WIDTH;
    stats->node_lanes.active_lanes += (uint64_t)used;
}

/* Walks the wide BVH for one ray. any == true stops at the first hit. */
LANES_BODY bool wide_walk(const lanes_wbvh *wb, const lanes_bvh2 *b, lanes_accuracy accuracy,
                          const lanes_ray *ray, bool any, lanes_hit *hit, lanes_trace_stats *stats)
{
    const lanes_precision prec = lanes_accuracy_precision(accuracy);
    const lanes_tri_algo algo = prec.algo;
    stack_entry stack[STACK_SIZE];
    float tentry[WIDE_WIDTH];
    float tfar = ray->tfar;
    bool found = false;
    if (!(ray->tnear <= ray->tfar)) return false;
    node_ray nr = node_ray_setup(ray, prec.exit_scale);
    wide_setup w = wide_setup_ray(algo, ray, &b->tris);
    int sp = 0;
    stack[sp++] = (stack_entry){0, 0, ray->tnear};
    while (sp > 0) {
        stack_entry e = stack[--sp];
        /* A node with one hit child goes straight on to it, without the
         * stack: the common case below the top levels. */
        for (;;) {
            if (e.t > tfar * prec.exit_scale) break;
            if (e.count > 0) {
                if (stats) stats->leaves_visited++;
                if (any) {
                    if (leaf_any(algo, &w, e.ref, e.count, stats)) return true;
                } else {
                    found |= leaf_closest(algo, &w, b, e.ref, e.count, &tfar, hit, stats);
                }
                break;
            }
            const float *node = wb->bounds + (size_t)e.ref * 6 * WIDE_WIDTH;
            uint32_t bits = node_hits(node, &nr, tfar, tentry);
            if (stats) count_node(stats, wb, e.ref);
            if (bits == 0) break;
            if ((bits & (bits - 1)) == 0) {
                int j = __builtin_ctz(bits);
                size_t slot = (size_t)e.ref * WIDE_WIDTH + (size_t)j;
                e = (stack_entry){wb->child[slot], wb->count[slot], tentry[j]};
                continue;
            }
            /* Push the hit children farthest first, so the nearest is
             * popped next: an insertion sort of at most WIDE_WIDTH entries. */
            stack_entry *base = stack + sp;
            int n = 0;
            while (bits) {
                int j = __builtin_ctz(bits);
                bits &= bits - 1;
                size_t slot = (size_t)e.ref * WIDE_WIDTH + (size_t)j;
                stack_entry c = {wb->child[slot], wb->count[slot], tentry[j]};
                int k = n++;
                while (k > 0 && base[k - 1].t < c.t) {
                    base[k] = base[k - 1];
                    k--;
                }
                base[k] = c;
            }
            sp += n;
            break;
        }
    }
    return found;
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
    wide_setup w = wide_setup_ray(algo, ray, &b->tris);
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
                if (leaf_any(algo, &w, nd->first, nd->count, stats)) return true;
            } else {
                found |= leaf_closest(algo, &w, b, nd->first, nd->count, &tfar, hit, stats);
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

LANES_BODY void trace_wide_body(const lanes_wbvh *wb, const lanes_bvh2 *b, lanes_accuracy accuracy,
                                const lanes_ray *rays, size_t n, lanes_hit *hits,
                                lanes_trace_stats *stats)
{
    for (size_t i = 0; i < n; i++) {
        hits[i] = no_hit();
        wide_walk(wb, b, accuracy, &rays[i], false, &hits[i], stats);
    }
    if (stats) stats->rays += n;
}

LANES_BODY void occluded_wide_body(const lanes_wbvh *wb, const lanes_bvh2 *b, lanes_accuracy accuracy,
                                   const lanes_ray *rays, size_t n, uint8_t *occluded,
                                   lanes_trace_stats *stats)
{
    for (size_t i = 0; i < n; i++) occluded[i] = wide_walk(wb, b, accuracy, &rays[i], true, NULL, stats);
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

/* The entry points: each body instantiated with and without counting. */
LANES_KERNELS_TRAVERSE(LANES_KERNEL_ENTRY)
