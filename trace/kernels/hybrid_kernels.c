/* Ray packets through the wide BVH, written once and compiled per
 * instruction set. LANES_W consecutive rays (one per lane) visit the tree
 * together: at a node each child's box is tested against all rays of the
 * packet at once (SIMD across the rays, the node fetched once for all of
 * them), and when SWITCH_AT rays (one) or fewer are left at a node, they
 * go on alone through the single-ray core (wide_core.h) from there: hybrid
 * traversal (Benthin, Wald, Woop, Ernst and Mark 2012; Embree's
 * BVHNIntersectorKHybrid). Leaves are tested per ray with the single-ray
 * block test.
 *
 * Every box and triangle test computes, per ray, what the single-ray
 * traversal computes (the same planes, operations and operand order), so
 * each ray gets trace_wide's hit bit for bit, except where the visiting
 * order decides, which a packet may change: two leaves with hits at the
 * same distance (the one visited last wins: equal t, another triangle), and
 * a hit whose float t lies outside or on its box's boundary, so that the
 * box is culled in one order and not in the other (tests/test_traversal.c
 * judges each such ray by brute force).
 *
 * The caller makes the packets coherent by its ray order (camera rays in
 * pixel tiles, shadow rays from them), as with Embree's coherent packets. */
#include "trace/kernels/kernel_decls.h"
#include "trace/kernels/wide_core.h"

#define PACKET_RAYS LANES_W

/* A packet goes on together while more than SWITCH_AT of its rays need a
 * node; at or below it they continue as single rays. Embree switches at 3
 * of 4, 7 of 8 and 14 of 16 rays; for lanes that was the slowest choice.
 * Measured on dragon (AMD EPYC Zen 4, family 0x19 model 0x11; hybrid/wide,
 * paired medians of 11 runs): at 14 of 16 rays, primary 0.93x and shadow
 * 0.76x; at 8 of 16, 1.13x and 0.98x; at 1 of 16, 1.43x and 1.27x; at 7 of
 * 8, 1.16x and 0.92x; at 1 of 8, 1.26x and 1.20x. A packet's node test is
 * a frustum test plus one exact test per child it keeps (2-4 on these
 * scenes), so it beats single rays' one test per ray while more rays than
 * that are live, and a ray that goes on alone pays its own set-up at every
 * node where it leaves a packet. */
#if PACKET_RAYS > 1
#define SWITCH_AT 1
#else
#define SWITCH_AT PACKET_RAYS
#endif

/* The packet's rays, one per lane of a node_ray (which otherwise holds one
 * ray broadcast): they share the direction's octant, so the near and far
 * planes are the same for all, and slab_t computes each lane's own ray. */
typedef struct {
    node_ray r;
    /* The packet's interval bounds, for the frustum test of a whole node:
     * per axis the origin bound that makes the near
     * (far) plane nearest (farthest), and the range of 1/d; an axis with an
     * infinite 1/d is left out of the test. */
    bool f_axis[3];
    vfloat f_on[3], f_of[3], f_rmin[3], f_rmax[3];
    float f_tnear;
} packet_rays;

/* The live rays of rays[0 .. m): tnear <= tfar. */
static inline uint32_t packet_live(const lanes_ray *rays, size_t m)
{
    uint32_t bits = 0;
    for (size_t i = 0; i < m; i++)
        if (rays[i].tnear <= rays[i].tfar) bits |= 1u << i;
    return bits;
}

/* Whether the live rays of a group share an octant. Tested ray by ray
 * before any set-up: incoherent groups (diffuse rays) differ by the
 * second ray, so that they cost a few instructions and not a packet's
 * set-up (which added 5% to diffuse rays, measured by callgrind). */
static inline bool one_octant(const lanes_ray *rays, uint32_t live)
{
    const unsigned first = ray_octant(&rays[__builtin_ctz(live)]);
    for (uint32_t rest = live & (live - 1); rest; rest &= rest - 1)
        if (ray_octant(&rays[__builtin_ctz(rest)]) != first) return false;
    return true;
}

/* The packet of rays[0 .. m) with live rays live (not 0), which share an
 * octant (one_octant). Lanes of dead
 * rays repeat a live ray, so that they compute nothing odd. Returns false
 * when the group is better traced ray by ray: in fast mode, a ray's
 * o * (1/d) overflows, so that it takes the exact slab form while the
 * others take the FMA form, and a packet has one form. */
LANES_BODY bool packet_setup(const lanes_ray *rays, uint32_t live, lanes_accuracy accuracy, float exit_scale,
                             packet_rays *p, int *slab)
{
    /* the fields of lane i's ray are gathered from rays[i] (or the first
     * live ray's) at index[i] + offset */
    enum { RAY_FLOATS = sizeof(lanes_ray) / sizeof(float) };
    const float *base = (const float *)(const void *)rays;
    const int first = __builtin_ctz(live);
    int32_t index[PACKET_RAYS];
    for (int i = 0; i < PACKET_RAYS; i++) index[i] = (live & (1u << i) ? i : first) * RAY_FLOATS;
    const vint idx = vi_loadu(index);
    const vfloat flt_max = vf_set1(FLT_MAX), zero = vf_zero();
    vmask finite = vm_true();
    for (int a = 0; a < 3; a++) {
        p->r.o[a] = vf_gather(base + offsetof(lanes_ray, o) / sizeof(float) + a, idx);
        p->r.rd[a] = vf_gather(base + offsetof(lanes_ray, rd) / sizeof(float) + a, idx);
        p->r.ord[a] = vf_mul(p->r.o[a], p->r.rd[a]);
        finite = vm_and(finite, vf_le(vf_abs(p->r.ord[a]), flt_max));
        const uint32_t neg = vm_bits(vf_lt(p->r.rd[a], zero));
        p->r.near[a] = neg ? a + 3 : a;
        p->r.far[a] = neg ? a : a + 3;
        const float omin = vf_reduce_min(p->r.o[a]), omax = vf_reduce_max(p->r.o[a]);
        p->f_axis[a] = vm_all(vf_le(vf_abs(p->r.rd[a]), flt_max));
        p->f_on[a] = vf_set1(neg ? omin : omax);
        p->f_of[a] = vf_set1(neg ? omax : omin);
        p->f_rmin[a] = vf_set1(vf_reduce_min(p->r.rd[a]));
        p->f_rmax[a] = vf_set1(vf_reduce_max(p->r.rd[a]));
    }
    p->r.tnear = vf_gather(base + offsetof(lanes_ray, tnear) / sizeof(float), idx);
    p->f_tnear = vf_reduce_min(p->r.tnear);
    p->r.exit_scale = vf_set1(exit_scale);
    if (exit_scale != 1.0f) {
        *slab = SLAB_ROBUST;
        return true;
    }
    *slab = accuracy == LANES_ACCURACY_FAST ? SLAB_FMA : SLAB_EXACT;
    return vm_all(finite) || accuracy != LANES_ACCURACY_FAST;
}

/* Child j of node against every ray: the rays that enter it before their
 * tfar, and their entry distances in *tin (node_hits' arithmetic per ray).
 * Skipping it, so that a child the frustum keeps takes every active ray
 * with the frustum's entry bound (the frustum alone deciding the descent),
 * slowed the packets on dragon, sponza-bunny and 20-bunnies (avx2, Zen 4,
 * clang 14, alternating runs): primary rays to 0.73-0.94x, shadow rays,
 * whose frusta from many origins are loose, to 0.03-0.13x. Each ray then
 * tests leaves its own box test would have culled. */
LANES_BODY vmask packet_child(const float *node, int j, const packet_rays *p, int slab, vfloat tfar,
                              vfloat *tin_out)
{
    vfloat tin = p->r.tnear, tout = tfar;
    for (int a = 0; a < 3; a++) {
        tin = vf_max(slab_t(slab, vf_set1(node[p->r.near[a] * WIDE_WIDTH + j]), &p->r, a), tin);
        tout = vf_min(slab_t(slab, vf_set1(node[p->r.far[a] * WIDE_WIDTH + j]), &p->r, a), tout);
    }
    if (slab == SLAB_ROBUST) tout = vf_mul(tout, p->r.exit_scale);
    *tin_out = tin;
    return vf_le(tin, tout);
}

/* The frustum test (Reshetov et al. 2005; Embree's coherent packets): all
 * children of a node at once against the packet's interval bounds, as one
 * ray's node test is. Bit j clear: no ray of the packet enters child j.
 * Per axis, a ray enters at (near - o) / d and leaves at (far - o) / d; the
 * bound picks the o and 1/d of the packet's ranges that make the entry
 * smallest and the exit largest. Each is rounded once or twice where the
 * ray's own distance is rounded once (or fused), so both are widened by
 * 2^-20 of their size, far more than those roundings. tentry[j]: a lower
 * bound of the rays' entries, the children's visiting order. */
LANES_BODY uint32_t frustum_children(const float *node, const packet_rays *p, int slab, float tfar,
                                     float *tentry)
{
    const vfloat zero = vf_zero(), slack = vf_set1(0x1p-20f);
    uint32_t bits = 0;
    for (int j = 0; j < WIDE_WIDTH; j += LANES_W) {
        vfloat tin = vf_set1(p->f_tnear), tout = vf_set1(tfar);
        for (int a = 0; a < 3; a++) {
            if (!p->f_axis[a]) continue;
            vfloat xn = vf_sub(vf_load(node + p->r.near[a] * WIDE_WIDTH + j), p->f_on[a]);
            vfloat xf = vf_sub(vf_load(node + p->r.far[a] * WIDE_WIDTH + j), p->f_of[a]);
            tin = vf_max(vf_mul(xn, vf_select(vf_ge(xn, zero), p->f_rmin[a], p->f_rmax[a])), tin);
            tout = vf_min(vf_mul(xf, vf_select(vf_ge(xf, zero), p->f_rmax[a], p->f_rmin[a])), tout);
        }
        tin = vf_sub(tin, vf_mul(vf_abs(tin), slack));
        tout = vf_add(tout, vf_mul(vf_abs(tout), slack));
        if (slab == SLAB_ROBUST) tout = vf_mul(tout, p->r.exit_scale);
        vf_storeu(tentry + j, tin);
        bits |= vm_bits(vf_le(tin, tout)) << j;
    }
    return bits;
}

/* Where the packet stands: a node or leaf, the rays that entered it and
 * their entry distances. */
typedef struct {
    uint32_t ref, rays;
    float key; /* the nearest entry among them: the visiting order */
} packet_entry;

typedef struct {
    const lanes_wbvh *wb;
    lanes_accuracy accuracy;
    lanes_precision prec;
    const lanes_ray *rays;
    lanes_hit *hits;     /* closest hit: per ray */
    uint8_t *occluded;   /* occlusion: per ray */
    float tfar[PACKET_RAYS];       /* each ray's best distance so far */
    uint32_t live;       /* rays not yet finished */
    /* each ray's leaf test set-up, made when it first needs one: a ray
     * meets several leaves and subtrees, and the set-up costs about as
     * much as a block test */
    uint32_t setup_ready;
    wide_setup setup[PACKET_RAYS];
} packet_state;

LANES_BODY const wide_setup *ray_setup(packet_state *s, int i)
{
    if (!(s->setup_ready & (1u << i))) {
        wide_setup_init(&s->setup[i], s->prec.algo, &s->rays[i], NULL);
        s->setup_ready |= 1u << i;
    }
    return &s->setup[i];
}

/* The single-ray walks, kept out of line: inlined, they would be copied
 * into every packet_walk instance (slab form x closest/any x counted),
 * and the function grew past 100 KB of code. One copy per (any, counted):
 * the branch on stats and any is decided here, as in trace_wide. */
#define WALK_ALONE(name, ANY, STATS)                                                                  \
    static __attribute__((noinline)) bool name(const lanes_wbvh *wb, lanes_tri_algo algo, int slab,   \
                                               const node_ray *nr, const wide_setup *w, wide_entry e, \
                                               float *tfar, lanes_hit *hit, lanes_trace_stats *stats) \
    {                                                                                                 \
        (void)stats;                                                                                  \
        return wide_walk_from(wb, algo, slab, nr, w, e, tfar, ANY, hit, STATS);                       \
    }
WALK_ALONE(walk_closest, false, NULL)
WALK_ALONE(walk_closest_counted, false, stats)
WALK_ALONE(walk_any, true, NULL)
WALK_ALONE(walk_any_counted, true, stats)

/* Ray i continues alone from ref, entered at distance t. */
LANES_BODY void finish_alone(packet_state *s, int i, uint32_t ref, float t, bool any,
                             lanes_trace_stats *stats)
{
    const lanes_ray *r = &s->rays[i];
    node_ray nr;
    const int slab = node_ray_init(&nr, r, s->accuracy, s->prec.exit_scale);
    const wide_setup *w = ray_setup(s, i);
    const wide_entry e = {ref, t};
    if (any) {
        bool found = stats ? walk_any_counted(s->wb, s->prec.algo, slab, &nr, w, e, &s->tfar[i], NULL, stats)
                           : walk_any(s->wb, s->prec.algo, slab, &nr, w, e, &s->tfar[i], NULL, NULL);
        if (found) {
            s->occluded[i] = 1;
            s->live &= ~(1u << i);
        }
    } else if (stats) {
        walk_closest_counted(s->wb, s->prec.algo, slab, &nr, w, e, &s->tfar[i], &s->hits[i], stats);
    } else {
        walk_closest(s->wb, s->prec.algo, slab, &nr, w, e, &s->tfar[i], &s->hits[i], NULL);
    }
}

/* A leaf, ray by ray. */
LANES_BODY void packet_leaf(packet_state *s, uint32_t ref, uint32_t act, bool any, lanes_trace_stats *stats)
{
    while (act) {
        int i = __builtin_ctz(act);
        act &= act - 1;
        const wide_setup *w = ray_setup(s, i);
        if (stats) stats->leaves_visited++;
        if (!any) {
            leaf_closest(s->wb, s->prec.algo, w, ref, &s->tfar[i], &s->hits[i], stats);
        } else if (leaf_any(s->wb, s->prec.algo, w, ref, stats)) {
            s->occluded[i] = 1;
            s->live &= ~(1u << i);
        }
    }
}

/* Inserts c into base[0 .. n), kept in decreasing key. */
static inline int insert_packet_entry(packet_entry *base, vfloat *base_t, int n, packet_entry c, vfloat ct)
{
    int k = n;
    while (k > 0 && base[k - 1].key < c.key) {
        base[k] = base[k - 1];
        base_t[k] = base_t[k - 1];
        k--;
    }
    base[k] = c;
    base_t[k] = ct;
    return n + 1;
}

LANES_BODY void packet_walk(packet_state *s, const packet_rays *p, int slab, bool any, lanes_trace_stats *stats)
{
    packet_entry stack[STACK_SIZE];
    vfloat stack_t[STACK_SIZE];
    float tin_lanes[PACKET_RAYS], fkey[WIDE_WIDTH];
    float ftfar = 0.0f; /* the frustum's far end: the largest tfar of a live ray */
    bool ftfar_stale = true;
    int sp = 0;
    packet_entry e = {0, s->live, 0.0f};
    vfloat et = p->r.tnear;
    for (;;) {
        vfloat tfar = vf_loadu(s->tfar);
        /* the rays that still need this entry: not finished, and it is not
         * beyond their best hit */
        uint32_t act = e.rays & s->live & ~vm_bits(vf_gt(et, vf_mul(tfar, p->r.exit_scale)));
        if (act == 0) goto pop;
        if (__builtin_popcount(act) <= SWITCH_AT) {
            vf_storeu(tin_lanes, et);
            while (act) {
                int i = __builtin_ctz(act);
                act &= act - 1;
                finish_alone(s, i, e.ref, tin_lanes[i], any, stats);
            }
            ftfar_stale = true;
            if (any && s->live == 0) return;
            goto pop;
        }
        if (lanes_wref_is_leaf(e.ref)) {
            packet_leaf(s, e.ref, act, any, stats);
            ftfar_stale = true;
            if (any && s->live == 0) return;
            goto pop;
        }
        {
            const float *node = (const float *)(const void *)(s->wb->nodes + (size_t)e.ref * NODE_BYTES);
            const uint32_t *ref = (const uint32_t *)(const void *)(node + 6 * WIDE_WIDTH);
            vmask in_act = vm_from_bits(act);
            packet_entry *base = stack + sp;
            vfloat *base_t = stack_t + sp;
            int n = 0, children = 0, tested = 0;
            while (children < WIDE_WIDTH && ref[children] != LANES_WBVH_EMPTY) children++;
            if (ftfar_stale) {
                ftfar = vf_reduce_max(vf_select(vm_from_bits(s->live), tfar, vf_set1(-INFINITY)));
                ftfar_stale = false;
            }
            uint32_t cand = frustum_children(node, p, slab, ftfar, fkey) & ((1u << children) - 1);
            while (cand) {
                int j = __builtin_ctz(cand);
                cand &= cand - 1;
                vfloat tin;
                vmask hit = vm_and(in_act, packet_child(node, j, p, slab, tfar, &tin));
                tested++;
                if (vm_none(hit)) continue;
                packet_entry c = {ref[j], vm_bits(hit), fkey[j]};
                n = insert_packet_entry(base, base_t, n, c, tin);
            }
            if (stats) {
                stats->nodes_visited++;
                /* the frustum test, one lane per child, and the exact
                 * tests of the children it kept, one lane per ray */
                int fops = (WIDE_WIDTH + LANES_W - 1) / LANES_W;
                stats->node_lanes.vector_ops += (uint64_t)(fops + tested);
                stats->node_lanes.lane_slots += (uint64_t)(fops * LANES_W + tested * PACKET_RAYS);
                stats->node_lanes.active_lanes +=
                    (uint64_t)children + (uint64_t)tested * (uint64_t)__builtin_popcount(act);
            }
            if (n == 0) goto pop;
            /* the nearest next, the rest pushed farthest first */
            for (int k = 0; k < n - 1; k++) prefetch_child(s->wb, base[k].ref);
            sp += n - 1;
            e = base[n - 1];
            et = base_t[n - 1];
            continue;
        }
    pop:
        if (sp == 0) return;
        sp--;
        e = stack[sp];
        et = stack_t[sp];
    }
}

/* Rays rays[0 .. m), m <= PACKET_RAYS, as one packet. */
LANES_BODY void hybrid_group(const lanes_wbvh *wb, lanes_accuracy accuracy, const lanes_ray *rays, size_t m,
                             bool any, lanes_hit *hits, uint8_t *occluded, lanes_trace_stats *stats)
{
    packet_state s;
    s.wb = wb;
    s.accuracy = accuracy;
    s.prec = lanes_accuracy_precision(accuracy);
    s.rays = rays;
    s.hits = hits;
    s.occluded = occluded;
    s.setup_ready = 0;
    s.live = packet_live(rays, m);
    packet_rays p;
    int slab;
    /* Rays of several octants go ray by ray: each ray's own nearest-first
     * order beats a common one, and the frustum needs one octant. */
    if (s.live == 0 || !one_octant(rays, s.live) ||
        !packet_setup(rays, s.live, accuracy, s.prec.exit_scale, &p, &slab)) {
        /* trace_wide's own entry, which also counts the rays: inlined
         * here, the same loop ran 9% more instructions (callgrind) */
        if (any)
            LANES_KFN(lanes_occluded_wide)(wb, accuracy, rays, m, occluded, stats);
        else
            LANES_KFN(lanes_trace_wide)(wb, accuracy, rays, m, hits, stats);
        return;
    }
    if (stats) stats->rays += m;
    for (size_t i = 0; i < m; i++) {
        if (any)
            occluded[i] = 0;
        else
            hits[i] = (lanes_hit){INFINITY, 0.0f, 0.0f, LANES_NO_HIT};
    }
    for (size_t i = 0; i < PACKET_RAYS; i++) s.tfar[i] = i < m ? rays[i].tfar : -INFINITY;
    if (slab == SLAB_FMA)
        packet_walk(&s, &p, SLAB_FMA, any, stats);
    else if (slab == SLAB_ROBUST)
        packet_walk(&s, &p, SLAB_ROBUST, any, stats);
    else
        packet_walk(&s, &p, SLAB_EXACT, any, stats);
}

LANES_BODY void trace_hybrid_body(const lanes_wbvh *wb, lanes_accuracy accuracy, const lanes_ray *rays,
                                  size_t n, lanes_hit *hits, lanes_trace_stats *stats)
{
    for (size_t b = 0; b < n; b += PACKET_RAYS)
        hybrid_group(wb, accuracy, rays + b, n - b < PACKET_RAYS ? n - b : PACKET_RAYS, false, hits + b, NULL, stats);
}

LANES_BODY void occluded_hybrid_body(const lanes_wbvh *wb, lanes_accuracy accuracy, const lanes_ray *rays,
                                     size_t n, uint8_t *occluded, lanes_trace_stats *stats)
{
    for (size_t b = 0; b < n; b += PACKET_RAYS)
        hybrid_group(wb, accuracy, rays + b, n - b < PACKET_RAYS ? n - b : PACKET_RAYS, true, NULL, occluded + b, stats);
}

LANES_KERNELS_HYBRID(LANES_KERNEL_ENTRY)
