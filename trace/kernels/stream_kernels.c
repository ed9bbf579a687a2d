/* Ray streams through the wide BVH, written once and compiled per
 * instruction set: the rays are sorted into their direction octants as
 * they come, and each group of up to GROUP rays of one octant walks the
 * tree together, as Embree's rtcOccluded1M / rtcIntersect1M do (Wald,
 * Benthin and Boulos 2008, "Getting rid of packets"; Tsakok 2009, MBVH/RS).
 * A stack entry is a node and the bit set of the group's rays that entered
 * it; at a node, each of those rays is tested against all children at once
 * (SIMD across the children, the single-ray node test) with its own tfar,
 * the node's planes loaded once for the group.
 *
 * Occlusion: a ray that finds a hit leaves the group. Each ray makes
 * occluded_wide's tests with the same tfar, which occlusion never shrinks,
 * so it enters the same leaves and the answer is occluded_wide's, bit for
 * bit; only the order of the leaves differs.
 *
 * Closest hit: the children go nearest first as the group's first ray sees
 * them, which for coherent rays is near enough every ray's order. A ray's
 * tfar shrinks with its hits, so it is the closest hit of trace_wide but
 * where the order decides (a tie between leaves, a hit within rounding of
 * its box's boundary), as for hybrid packets.
 *
 * In fast mode a ray whose o * (1/d) overflows takes the exact slab form
 * and is traced alone. */
#include "trace/kernels/kernel_decls.h"
#include "trace/kernels/wide_core.h"

/* Rays in a group: one bit each of a stack entry's set. Embree uses 32. */
#define GROUP 32

typedef struct {
    uint32_t ref;  /* the node or leaf */
    uint32_t rays; /* bit i: ray i of the group entered it */
} group_entry;

/* A group's rays, SoA for the per-ray broadcasts of the node test; the
 * leaf test's set-up is made the first time a ray reaches a leaf. */
typedef struct {
    float o[3][GROUP], rd[3][GROUP], tnear[GROUP], tfar[GROUP];
    const lanes_ray *ray[GROUP];
    uint32_t id[GROUP];
    int near[3], far[3];
    wide_setup w[GROUP];
} ray_group;

/* Ray i of the group as the node test takes a ray, filled in place (see
 * node_ray_init); the compiler keeps only the broadcasts the slab form
 * reads. */
LANES_BODY void group_ray(node_ray *r, const ray_group *g, int i, vfloat exit_scale)
{
    for (int a = 0; a < 3; a++) {
        r->near[a] = g->near[a];
        r->far[a] = g->far[a];
        r->o[a] = vf_set1(g->o[a][i]);
        r->rd[a] = vf_set1(g->rd[a][i]);
        r->ord[a] = vf_set1(g->o[a][i] * g->rd[a][i]);
    }
    r->tnear = vf_set1(g->tnear[i]);
    r->exit_scale = exit_scale;
}

/* Where a stream's answers go: occluded[] for any hits, else hits[]. */
typedef struct {
    uint8_t *occluded;
    lanes_hit *hits;
} stream_out;

/* Tests the group's rays in `rays` against a leaf; returns those done with
 * the tree (occlusion: those that hit something, their occluded[] set;
 * closest hit: none, their tfar and hits[] updated). */
LANES_BODY uint32_t group_leaf(const lanes_wbvh *wb, lanes_tri_algo algo, bool any, ray_group *g, uint32_t ref,
                               uint32_t rays, uint32_t *ready, stream_out out, lanes_trace_stats *stats)
{
    uint32_t done = 0;
    for (uint32_t todo = rays; todo; todo &= todo - 1) {
        const int i = __builtin_ctz(todo);
        if (!(*ready & (1u << i))) {
            wide_setup_init(&g->w[i], algo, g->ray[i], NULL);
            *ready |= 1u << i;
        }
        if (stats) stats->leaves_visited++;
        if (!any) {
            leaf_closest(wb, algo, &g->w[i], ref, &g->tfar[i], &out.hits[g->id[i]], stats);
        } else if (leaf_any(wb, algo, &g->w[i], ref, stats)) {
            done |= 1u << i;
            out.occluded[g->id[i]] = 1;
        }
    }
    return done;
}

/* The children a closest-hit group enters, nearest first as the group's
 * first ray sees them, onto the stack but the nearest, which *e becomes. */
LANES_BODY void push_by_leader(const lanes_wbvh *wb, const uint32_t *ref, const uint32_t *child,
                               const float *lead_tin, group_entry *stack, int *sp, group_entry *e)
{
    wide_entry order[WIDE_WIDTH];
    int n = 0;
    for (int j = 0; j < WIDE_WIDTH; j++)
        if (child[j]) n = insert_nearest_last(order, n, (wide_entry){(uint32_t)j, lead_tin[j]});
    e->rays = 0;
    if (n == 0) return;
    for (int k = 0; k < n - 1; k++) {
        const uint32_t j = order[k].ref;
        prefetch_child(wb, ref[j]);
        stack[(*sp)++] = (group_entry){ref[j], child[j]};
    }
    *e = (group_entry){ref[order[n - 1].ref], child[order[n - 1].ref]};
}

LANES_BODY void group_walk(const lanes_wbvh *wb, lanes_tri_algo algo, int slab, bool any, ray_group *g,
                           uint32_t live, stream_out out, lanes_trace_stats *stats)
{
    const vfloat exit_scale = vf_set1(slab == SLAB_ROBUST ? LANES_ROBUST_SCALE : 1.0f);
    group_entry stack[STACK_SIZE];
    int sp = 0;
    uint32_t done = 0, ready = 0;
    group_entry e = {0, live};
    for (;;) {
        const uint32_t rays = e.rays & ~done;
        if (rays && lanes_wref_is_leaf(e.ref)) {
            done |= group_leaf(wb, algo, any, g, e.ref, rays, &ready, out, stats);
        } else if (rays) {
            const float *node = (const float *)(const void *)(wb->nodes + (size_t)e.ref * NODE_BYTES);
            const uint32_t *ref = (const uint32_t *)(const void *)(node + 6 * WIDE_WIDTH);
            node_planes planes;
            load_planes(node, g->near, g->far, &planes);
            /* lane j of vector c: the rays that enter child c * LANES_W + j */
            vint entered[NODE_VECTORS];
            float lead_tin[WIDE_WIDTH];
            for (int c = 0; c < NODE_VECTORS; c++) entered[c] = vi_zero();
            for (uint32_t todo = rays; todo; todo &= todo - 1) {
                const int i = __builtin_ctz(todo);
                node_ray r;
                group_ray(&r, g, i, exit_scale);
                const vint bit = vi_set1((int32_t)(1u << i));
                const vfloat tf = vf_set1(g->tfar[i]);
                for (int c = 0; c < NODE_VECTORS; c++) {
                    vfloat tin;
                    vmask m = planes_test(&planes, &r, slab, tf, c, &tin);
                    entered[c] = vi_or(entered[c], vi_select(m, bit, vi_zero()));
                    if (!any && todo == rays) vf_storeu(lead_tin + c * LANES_W, tin);
                }
                if (stats) count_node(stats, ref);
            }
            uint32_t child[WIDE_WIDTH];
            for (int c = 0; c < NODE_VECTORS; c++) vi_storeu((int32_t *)child + c * LANES_W, entered[c]);
            if (!any) {
                push_by_leader(wb, ref, child, lead_tin, stack, &sp, &e);
                if (e.rays) continue;
            } else {
                /* any hit will do: on with the first child entered, the
                 * others pushed */
                e.rays = 0;
                for (int j = 0; j < WIDE_WIDTH; j++) {
                    if (!child[j]) continue;
                    group_entry c = {ref[j], child[j]};
                    if (e.rays) {
                        prefetch_child(wb, c.ref);
                        stack[sp++] = c;
                    } else {
                        e = c;
                    }
                }
                if (e.rays) continue;
            }
        }
        if (sp == 0) break;
        e = stack[--sp];
    }
}

/* rays[id[0 .. m)], which share an octant and slab form, as one group. */
LANES_BODY void trace_group(const lanes_wbvh *wb, lanes_tri_algo algo, int slab, bool any, const lanes_ray *rays,
                            const uint32_t *id, unsigned m, stream_out out, lanes_trace_stats *stats)
{
    ray_group g;
    for (unsigned i = 0; i < m; i++) {
        const lanes_ray *r = &rays[id[i]];
        for (int a = 0; a < 3; a++) {
            g.o[a][i] = r->o[a];
            g.rd[a][i] = r->rd[a];
        }
        g.tnear[i] = r->tnear;
        g.tfar[i] = r->tfar;
        g.ray[i] = r;
        g.id[i] = id[i];
    }
    for (int a = 0; a < 3; a++) {
        g.near[a] = g.rd[a][0] < 0.0f ? a + 3 : a;
        g.far[a] = g.rd[a][0] < 0.0f ? a : a + 3;
    }
    const uint32_t live = m == GROUP ? ~0u : (1u << m) - 1;
    if (slab == SLAB_FMA)
        group_walk(wb, algo, SLAB_FMA, any, &g, live, out, stats);
    else if (slab == SLAB_ROBUST)
        group_walk(wb, algo, SLAB_ROBUST, any, &g, live, out, stats);
    else
        group_walk(wb, algo, SLAB_EXACT, any, &g, live, out, stats);
}

/* Both streams: the rays binned by octant, each bin traced when full and
 * what is left at the end. */
LANES_BODY void stream_body(const lanes_wbvh *wb, lanes_accuracy accuracy, const lanes_ray *rays, size_t n,
                            bool any, stream_out out, lanes_trace_stats *stats)
{
    const lanes_precision prec = lanes_accuracy_precision(accuracy);
    const int slab = mode_slab(accuracy, prec.exit_scale);
    uint32_t bin[8][GROUP];
    unsigned count[8] = {0};
    for (size_t i = 0; i < n; i++) {
        const lanes_ray *r = &rays[i];
        if (any)
            out.occluded[i] = 0;
        else
            out.hits[i] = (lanes_hit){INFINITY, 0.0f, 0.0f, LANES_NO_HIT};
        if (!(r->tnear <= r->tfar)) continue;
        if (ray_slab(r, accuracy, prec.exit_scale) != slab) {
            bool hit = wide_ray(wb, accuracy, r, any, any ? NULL : &out.hits[i], stats);
            if (any) out.occluded[i] = hit;
            continue;
        }
        const unsigned o = ray_octant(r);
        bin[o][count[o]++] = (uint32_t)i;
        if (count[o] == GROUP) {
            trace_group(wb, prec.algo, slab, any, rays, bin[o], GROUP, out, stats);
            count[o] = 0;
        }
    }
    for (unsigned o = 0; o < 8; o++)
        if (count[o]) trace_group(wb, prec.algo, slab, any, rays, bin[o], count[o], out, stats);
    if (stats) stats->rays += n;
}

LANES_BODY void trace_stream_body(const lanes_wbvh *wb, lanes_accuracy accuracy, const lanes_ray *rays,
                                  size_t n, lanes_hit *hits, lanes_trace_stats *stats)
{
    stream_body(wb, accuracy, rays, n, false, (stream_out){NULL, hits}, stats);
}

LANES_BODY void occluded_stream_body(const lanes_wbvh *wb, lanes_accuracy accuracy, const lanes_ray *rays,
                                     size_t n, uint8_t *occluded, lanes_trace_stats *stats)
{
    stream_body(wb, accuracy, rays, n, true, (stream_out){occluded, NULL}, stats);
}

LANES_KERNELS_STREAM(LANES_KERNEL_ENTRY)
