/* Ray packets through the wide BVH, written once and compiled per
 * instruction set. LANES_W consecutive rays (one per lane) visit the tree
 * together: at a node each child's box is tested against all rays of the
 * packet at once (SIMD across the rays, the node fetched once for all of
 * them), and when few rays are left at a node, those go on one at a time
 * through the single-ray core (wide_core.h) from that node: hybrid
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
 * node; at or below it they continue as single rays. A packet node test
 * costs one vector test per child where a single ray tests all children in
 * one, so it pays only while nearly every ray uses it: Embree's thresholds
 * (3 of 4, 7 of 8, 14 of 16 rays), measured in lanes compare. */
#if PACKET_RAYS >= 16
#define SWITCH_AT 14
#elif PACKET_RAYS >= 8
#define SWITCH_AT 7
#elif PACKET_RAYS >= 4
#define SWITCH_AT 3
#else
#define SWITCH_AT PACKET_RAYS
#endif

/* The packet's rays in SoA, as node_ray holds one ray. They share the
 * direction's octant, so the near and far planes are the same for all, as
 * for a single ray. */
typedef struct {
    vfloat o[3], rd[3], ord[3], tnear, exit_scale;
    int near[3], far[3];
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

/* The packet of rays[0 .. m) with live rays live (not 0). Lanes of dead
 * rays repeat a live ray, so that they compute nothing odd. Returns false
 * when the group is better traced ray by ray: its rays point into more
 * than one octant (incoherent: each ray's own nearest-first order beats a
 * common one, and the frustum needs one octant), or, in fast mode, a ray's
 * o * (1/d) overflows, so that it takes the exact slab form while the
 * others take the FMA form, and a packet has one form. */
LANES_BODY bool packet_setup(const lanes_ray *rays, uint32_t live, lanes_accuracy accuracy, float exit_scale,
                             packet_rays *p, int *slab)
{
    float o[3][PACKET_RAYS], rd[3][PACKET_RAYS], ord[3][PACKET_RAYS], tnear[PACKET_RAYS];
    float omin[3] = {INFINITY, INFINITY, INFINITY}, omax[3] = {-INFINITY, -INFINITY, -INFINITY};
    float rmin[3] = {INFINITY, INFINITY, INFINITY}, rmax[3] = {-INFINITY, -INFINITY, -INFINITY};
    bool rfinite[3] = {true, true, true};
    const size_t first = (size_t)__builtin_ctz(live);
    p->f_tnear = INFINITY;
    bool finite = true;
    int neg_lanes[3] = {0, 0, 0};
    for (size_t i = 0; i < PACKET_RAYS; i++) {
        const lanes_ray *r = &rays[live & (1u << i) ? i : first];
        for (int a = 0; a < 3; a++) {
            o[a][i] = r->o[a];
            rd[a][i] = r->rd[a];
            ord[a][i] = r->o[a] * r->rd[a];
            finite = finite && fabsf(ord[a][i]) <= FLT_MAX;
            neg_lanes[a] += r->rd[a] < 0.0f;
            omin[a] = r->o[a] < omin[a] ? r->o[a] : omin[a];
            omax[a] = r->o[a] > omax[a] ? r->o[a] : omax[a];
            rmin[a] = r->rd[a] < rmin[a] ? r->rd[a] : rmin[a];
            rmax[a] = r->rd[a] > rmax[a] ? r->rd[a] : rmax[a];
            rfinite[a] = rfinite[a] && fabsf(r->rd[a]) <= FLT_MAX;
        }
        tnear[i] = r->tnear;
        p->f_tnear = r->tnear < p->f_tnear ? r->tnear : p->f_tnear;
    }
    bool one_octant = true;
    for (int a = 0; a < 3; a++) {
        p->o[a] = vf_loadu(o[a]);
        p->rd[a] = vf_loadu(rd[a]);
        p->ord[a] = vf_loadu(ord[a]);
        one_octant = one_octant && (neg_lanes[a] == 0 || neg_lanes[a] == PACKET_RAYS);
        p->near[a] = neg_lanes[a] ? a + 3 : a;
        p->far[a] = neg_lanes[a] ? a : a + 3;
        p->f_axis[a] = rfinite[a];
        p->f_on[a] = vf_set1(neg_lanes[a] ? omin[a] : omax[a]);
        p->f_of[a] = vf_set1(neg_lanes[a] ? omax[a] : omin[a]);
        p->f_rmin[a] = vf_set1(rmin[a]);
        p->f_rmax[a] = vf_set1(rmax[a]);
    }
    p->tnear = vf_loadu(tnear);
    p->exit_scale = vf_set1(exit_scale);
    if (exit_scale != 1.0f) {
        *slab = SLAB_ROBUST;
        return one_octant;
    }
    *slab = accuracy == LANES_ACCURACY_FAST ? SLAB_FMA : SLAB_EXACT;
    return one_octant && (finite || accuracy != LANES_ACCURACY_FAST);
}

LANES_BODY vfloat packet_slab(int slab, vfloat plane, const packet_rays *p, int a)
{
    if (slab == SLAB_FMA) return vf_fmsub(plane, p->rd[a], p->ord[a]);
    return vf_mul(vf_sub(plane, p->o[a]), p->rd[a]);
}

/* Child j of node against every ray: the rays that enter it before their
 * tfar, and their entry distances in *tin (node_hits' arithmetic per ray). */
LANES_BODY vmask packet_child(const float *node, int j, const packet_rays *p, int slab, vfloat tfar,
                              vfloat *tin_out)
{
    vfloat tin = p->tnear, tout = tfar;
    for (int a = 0; a < 3; a++) {
        tin = vf_max(packet_slab(slab, vf_set1(node[p->near[a] * WIDE_WIDTH + j]), p, a), tin);
        tout = vf_min(packet_slab(slab, vf_set1(node[p->far[a] * WIDE_WIDTH + j]), p, a), tout);
    }
    if (slab == SLAB_ROBUST) tout = vf_mul(tout, p->exit_scale);
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
            vfloat xn = vf_sub(vf_load(node + p->near[a] * WIDE_WIDTH + j), p->f_on[a]);
            vfloat xf = vf_sub(vf_load(node + p->far[a] * WIDE_WIDTH + j), p->f_of[a]);
            tin = vf_max(vf_mul(xn, vf_select(vf_ge(xn, zero), p->f_rmin[a], p->f_rmax[a])), tin);
            tout = vf_min(vf_mul(xf, vf_select(vf_ge(xf, zero), p->f_rmax[a], p->f_rmin[a])), tout);
        }
        tin = vf_sub(tin, vf_mul(vf_abs(tin), slack));
        tout = vf_add(tout, vf_mul(vf_abs(tout), slack));
        if (slab == SLAB_ROBUST) tout = vf_mul(tout, p->exit_scale);
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
} packet_state;

/* Ray i continues alone from ref, entered at distance t. */
LANES_BODY void finish_alone(packet_state *s, int i, uint32_t ref, float t, bool any,
                             lanes_trace_stats *stats)
{
    const lanes_ray *r = &s->rays[i];
    int slab;
    node_ray nr = node_ray_setup(r, s->accuracy, s->prec.exit_scale, &slab);
    wide_setup w;
    wide_setup_init(&w, s->prec.algo, r, NULL);
    bool found = wide_walk_from(s->wb, s->prec.algo, slab, &nr, &w, (wide_entry){ref, t}, &s->tfar[i], any,
                                any ? NULL : &s->hits[i], stats);
    if (any && found) {
        s->occluded[i] = 1;
        s->live &= ~(1u << i);
    }
}

/* A leaf, ray by ray. */
LANES_BODY void packet_leaf(packet_state *s, uint32_t ref, uint32_t act, bool any, lanes_trace_stats *stats)
{
    const unsigned char *blk = s->wb->blocks + (size_t)lanes_wref_block(ref) * BLOCK_BYTES;
    while (act) {
        int i = __builtin_ctz(act);
        act &= act - 1;
        wide_setup w;
        wide_setup_init(&w, s->prec.algo, &s->rays[i], NULL);
        if (stats) stats->leaves_visited++;
        if (!any) {
            leaf_closest(s->prec.algo, &w, blk, lanes_wref_blocks(ref), &s->tfar[i], &s->hits[i], stats);
        } else if (leaf_any(s->prec.algo, &w, blk, lanes_wref_blocks(ref), stats)) {
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
    vfloat et = p->tnear;
    for (;;) {
        vfloat tfar = vf_loadu(s->tfar);
        /* the rays that still need this entry: not finished, and it is not
         * beyond their best hit */
        uint32_t act = e.rays & s->live & ~vm_bits(vf_gt(et, vf_mul(tfar, p->exit_scale)));
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
    for (size_t i = 0; i < m; i++) {
        if (any)
            occluded[i] = 0;
        else
            hits[i] = (lanes_hit){INFINITY, 0.0f, 0.0f, LANES_NO_HIT};
    }
    s.live = packet_live(rays, m);
    if (s.live == 0) return;
    packet_rays p;
    int slab;
    if (!packet_setup(rays, s.live, accuracy, s.prec.exit_scale, &p, &slab)) {
        for (size_t i = 0; i < m; i++) {
            if (any)
                occluded[i] = wide_ray(wb, accuracy, &rays[i], true, NULL, stats);
            else
                wide_ray(wb, accuracy, &rays[i], false, &hits[i], stats);
        }
        return;
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
    if (stats) stats->rays += n;
}

LANES_BODY void occluded_hybrid_body(const lanes_wbvh *wb, lanes_accuracy accuracy, const lanes_ray *rays,
                                     size_t n, uint8_t *occluded, lanes_trace_stats *stats)
{
    for (size_t b = 0; b < n; b += PACKET_RAYS)
        hybrid_group(wb, accuracy, rays + b, n - b < PACKET_RAYS ? n - b : PACKET_RAYS, true, NULL, occluded + b, stats);
    if (stats) stats->rays += n;
}

LANES_KERNELS_HYBRID(LANES_KERNEL_ENTRY)
