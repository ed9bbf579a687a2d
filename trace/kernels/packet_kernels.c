/* Packet traversal of the BVH2, written once and compiled per instruction
 * set (Wu 2016 Alg. 2.1, 3.1, 3.2; Overbeck, Ramamoorthi and Mark 2008).
 *
 * A packet's rays are split into fixed groups of LANES_W rays; one SIMD
 * operation tests one group. Each node of the traversal is reached with a
 * list of groups and, per group, the mask of its rays that reached it:
 * - partition: the groups with a ray that hits the node are swapped to the
 *   front of the list; only they go on, and only their hitting rays count;
 * - ranged: the groups from the first to the last hitting one go on, in
 *   order, with every active ray.
 * Masks are kept per tree depth and per group id, so a sibling popped later
 * still finds its parent's masks whatever the other subtree reordered. */
#include "build/bvh.h"
#include "trace/kernels/box_core.h"
#include "trace/kernels/frustum_core.h"
#include "trace/kernels/kernel_decls.h"
#include "trace/kernels/triangle_core.h"

#define MAX_GROUPS ((LANES_PACKET_MAX_RAYS + LANES_W - 1) / LANES_W)
/* Below this many groups a node is tested group by group, without the
 * packet frustum. Instructions executed in the packet traversal of the
 * dragon scene's primary and shadow packets at avx2 (callgrind): frustum at
 * every node 1.13e9, none 0.95e9; from 4 groups 1.03e9, 16: 0.91e9,
 * 64: 0.89e9, 256: 0.94e9. */
#define FRUSTUM_MIN_GROUPS 32
/* The builder bounds the BVH2 depth by 64. */
#define MAX_DEPTH 66

typedef struct {
    uint32_t node;
    uint32_t ia;      /* partition: live groups at the list's front; ranged: first group */
    uint32_t last;    /* ranged: last group */
    uint32_t depth;   /* masks[depth] holds the masks this node is entered with */
} packet_entry;

typedef struct {
    uint32_t groups[MAX_GROUPS];
    uint16_t masks[MAX_DEPTH][MAX_GROUPS];
    uint32_t live_rays[LANES_PACKET_MAX_RAYS];
    uint16_t found[MAX_GROUPS]; /* closest hit: the rays of each group that have one */
} packet_scratch;

/* Is the box entirely outside the packet's frustum? The frustum cores are
 * SIMD across boxes; the one box is broadcast and lane 0 read. */
LANES_BODY bool frustum_culls_box(const lanes_frustum *f, const lanes_bvh2_node *nd)
{
    if (f->empty) return true;
    if (!f->valid) return false;
    vfloat lo[3] = {vf_set1(nd->min[0]), vf_set1(nd->min[1]), vf_set1(nd->min[2])};
    vfloat hi[3] = {vf_set1(nd->max[0]), vf_set1(nd->max[1]), vf_set1(nd->max[2])};
    vmask keep = boxes_interval(f, lo, hi);
    if (f->has_planes) keep = vm_and(keep, boxes_planes(f, lo, hi));
    return (vm_bits(keep) & 1u) == 0;
}

/* Wu's corner test: the four edge rays of the plane frustum all hit the box.
 * For rays from one point (primary, shadow) the box's cone of directions is
 * convex, so every ray between them hits too; otherwise it can only let a
 * group through that the leaf tests then reject, never lose a hit. */
static inline bool corner_rays_hit(const lanes_frustum *f, const lanes_bvh2_node *nd)
{
    if (!f->valid || !f->has_planes) return false;
    int k = f->k, a = (k + 1) % 3, b = (k + 2) % 3;
    for (int c = 0; c < 4; c++) {
        float o[3], d[3];
        o[k] = f->near;
        d[k] = f->ksign;
        o[a] = (c & 1) ? f->hi0[a] : f->lo0[a];
        d[a] = (c & 1) ? f->hi_slope[a] : f->lo_slope[a];
        o[b] = (c & 2) ? f->hi0[b] : f->lo0[b];
        d[b] = (c & 2) ? f->hi_slope[b] : f->lo_slope[b];
        float tin = 0.0f, tout = INFINITY;
        for (int x = 0; x < 3; x++) {
            float r = 1.0f / d[x];
            float t1 = (nd->min[x] - o[x]) * r, t2 = (nd->max[x] - o[x]) * r;
            float tn = r < 0.0f ? t2 : t1, tf = r < 0.0f ? t1 : t2;
            tin = tn > tin ? tn : tin;
            tout = tf < tout ? tf : tout;
        }
        if (!(tin <= tout * LANES_ROBUST_SCALE)) return false;
    }
    return true;
}

static inline lanes_triangle leaf_triangle(const lanes_triangles *t, size_t i)
{
    lanes_triangle tri = {{t->v0x[i], t->v0y[i], t->v0z[i]},
                          {t->v1x[i], t->v1y[i], t->v1z[i]},
                          {t->v2x[i], t->v2y[i], t->v2z[i]}};
    return tri;
}

/* The rays of one group with the given live mask. */
LANES_BODY lanes_vray group_rays(const lanes_rays *rays, uint32_t g, uint32_t mask, bool dir,
                                 bool rdir)
{
    lanes_vray r = lanes_load_rays(rays, NULL, (size_t)g * LANES_W, rays->count, dir, rdir);
    r.live = vm_and(r.live, vm_from_bits(mask));
    return r;
}

/* Tests the leaf's triangles against the groups list[0..count) (masks[g]),
 * recording closest hits or occlusion. */
LANES_BODY void packet_leaf(const lanes_bvh2 *b, const lanes_bvh2_node *nd,
                            const lanes_packet_options *opt, lanes_rays *rays,
                            const uint32_t *list, uint32_t count, bool ranged,
                            uint16_t *masks, packet_scratch *s, uint32_t *prim, float *u,
                            float *v, uint8_t *occluded, lanes_packet_stats *stats)
{
    uint32_t keep_bits[(64 + 31) / 32 + 1];
    bool culled_any = false;
    uint32_t ntri = nd->count;
    /* A frustum rebuilt from the rays that reached this leaf is tighter than
     * the packet's (Reshetov 2007; Wu 2.2.3). */
    if (opt->leaf_frustum && ntri > 1 && ntri <= 64) {
        uint32_t nlive = 0;
        for (uint32_t i = 0; i < count; i++) {
            uint32_t g = ranged ? list[0] + i : list[i];
            uint32_t m = masks[g];
            while (m) {
                uint32_t lane = (uint32_t)__builtin_ctz(m);
                m &= m - 1;
                s->live_rays[nlive++] = g * LANES_W + lane;
            }
        }
        lanes_frustum lf;
        LANES_FN(lanes_frustum_build)(rays, s->live_rays, nlive, &lf);
        lanes_triangles view = lanes_triangles_view(&b->tris, nd->first, ntri);
        LANES_FN(lanes_frustum_tris)(&lf, &view, ntri, LANES_CULL_BOTH, keep_bits, NULL);
        culled_any = true;
    }
    for (uint32_t k = 0; k < ntri; k++) {
        if (culled_any && !lanes_mask_get(keep_bits, k)) {
            if (stats) stats->triangles_culled++;
            continue;
        }
        uint32_t ti = nd->first + k;
        lanes_triangle tri = leaf_triangle(&b->tris, ti);
        const vint prim_id = vi_set1((int32_t)b->prim_index[ti]);
        if (stats) stats->triangles_tested++;
        for (uint32_t i = 0; i < count; i++) {
            uint32_t g = ranged ? list[0] + i : list[i];
            if (!masks[g]) continue;
            lanes_vray r = group_rays(rays, g, masks[g], true, false);
            if (stats) LANES_COUNT(&stats->tri_ops, r.live);
            tri_result h = tri_vs_rays(lanes_accuracy_precision(opt->accuracy).algo, &r, &tri, !opt->occlusion);
            if (vm_none(h.hit)) continue;
            size_t at = (size_t)g * LANES_W;
            if (opt->occlusion) {
                uint32_t bits = vm_bits(h.hit);
                lanes_store_hits(rays->tfar, at, rays->count, h.hit, vf_set1(-INFINITY));
                masks[g] &= (uint16_t)~bits;
                while (bits) {
                    occluded[at + (size_t)__builtin_ctz(bits)] = 1;
                    bits &= bits - 1;
                }
            } else {
                /* tfar is the closest hit so far: the test accepted t <= tfar,
                 * so ties go to the later triangle; take strictly nearer only.
                 * A ray's first hit may lie at its own tfar: [tnear, tfar]
                 * is closed. */
                vmask first = vm_not(vm_from_bits(s->found[g]));
                vmask nearer = vm_and(h.hit, vm_or(first, vf_lt(h.t, vf_load(rays->tfar + at))));
                s->found[g] |= (uint16_t)vm_bits(nearer);
                lanes_store_hits(rays->tfar, at, rays->count, nearer, h.t);
                lanes_store_hits(u, at, rays->count, nearer, h.u);
                lanes_store_hits(v, at, rays->count, nearer, h.v);
                lanes_store_hits((float *)(void *)prim, at, rays->count, nearer, vi_as_vf(prim_id));
            }
        }
    }
}

LANES_BODY void trace_packet_body(const lanes_bvh2 *b, const lanes_packet_options *opt,
                                  lanes_rays *rays, uint32_t *prim, float *u, float *v,
                                  uint8_t *occluded, lanes_packet_stats *stats)
{
    packet_scratch s;
    packet_entry stack[2 * MAX_DEPTH + 2];
    const bool ranged = opt->scheme == LANES_PACKET_RANGED;
    const float exit_scale = lanes_accuracy_precision(opt->accuracy).exit_scale;
    size_t n = rays->count < LANES_PACKET_MAX_RAYS ? rays->count : LANES_PACKET_MAX_RAYS;
    uint32_t ngroups = (uint32_t)((n + LANES_W - 1) / LANES_W);
    if (stats) {
        stats->packets++;
        stats->rays += n;
    }
    if (b->node_count == 0 || n == 0) return;

    /* Depth 0 masks: the active rays of each group. */
    uint32_t ia = 0;
    for (uint32_t g = 0; g < ngroups; g++) {
        lanes_vray r = lanes_load_rays(rays, NULL, (size_t)g * LANES_W, n, false, false);
        uint32_t m = vm_bits(vm_and(r.live, vf_le(r.tnear, r.tfar)));
        s.masks[0][g] = (uint16_t)m;
        s.found[g] = 0;
        if (m || ranged) s.groups[ia++] = g;
    }
    if (ia == 0) return;
    /* A rough direction of the packet, to visit the nearer child first. */
    float dir[3] = {rays->dx[0], rays->dy[0], rays->dz[0]};

    int sp = 0;
    stack[sp++] = (packet_entry){0, ranged ? 0 : ia, ranged ? ngroups - 1 : 0, 0};
    while (sp > 0) {
        packet_entry e = stack[--sp];
        const lanes_bvh2_node *nd = &b->nodes[e.node];
        const uint16_t *in = s.masks[e.depth];
        uint16_t *out = s.masks[e.depth + 1 < MAX_DEPTH ? e.depth + 1 : MAX_DEPTH - 1];
        lanes_box box = {{nd->min[0], nd->min[1], nd->min[2]}, {nd->max[0], nd->max[1], nd->max[2]}};

        /* The frustum test costs about as much as a few group tests: with
         * fewer groups left, testing them directly is cheaper. */
        uint32_t groups_here = ranged ? e.last - e.ia + 1 : e.ia;
        if (opt->frustum && groups_here >= FRUSTUM_MIN_GROUPS && frustum_culls_box(opt->frustum, nd)) {
            if (stats) stats->frustum_culled++;
            continue;
        }

        uint32_t go_first = 0, go_count = 0; /* the groups that go on */
        uint64_t live_rays = 0;
        if (ranged) {
            /* first and last group that hits, masks for the leaf from the
             * active rays */
            uint32_t first = e.ia, last = e.last;
            bool found = false;
            for (; first <= last; first++) {
                lanes_vray r = group_rays(rays, first, in[first], false, true);
                if (stats) LANES_COUNT(&stats->box_ops, r.live);
                vfloat entry;
                if (vm_any(box_vs_rays(&r, &box, &entry, exit_scale))) {
                    found = true;
                    break;
                }
            }
            if (!found) continue;
            for (; last > first; last--) {
                lanes_vray r = group_rays(rays, last, in[last], false, true);
                if (stats) LANES_COUNT(&stats->box_ops, r.live);
                vfloat entry;
                if (vm_any(box_vs_rays(&r, &box, &entry, exit_scale))) break;
            }
            for (uint32_t g = first; g <= last; g++) {
                lanes_vray r = lanes_load_rays(rays, NULL, (size_t)g * LANES_W, n, false, false);
                out[g] = (uint16_t)vm_bits(vm_and(r.live, vf_le(r.tnear, r.tfar)));
                live_rays += (uint64_t)__builtin_popcount(out[g]);
            }
            go_first = first;
            go_count = last - first + 1;
        } else if (opt->corner_test && opt->frustum && e.depth == 0 && corner_rays_hit(opt->frustum, nd)) {
            if (stats) stats->corner_all_hit++;
            for (uint32_t i = 0; i < e.ia; i++) {
                uint32_t g = s.groups[i];
                out[g] = in[g];
                live_rays += (uint64_t)__builtin_popcount(out[g]);
            }
            go_count = e.ia;
        } else {
            uint32_t ie = 0;
            for (uint32_t i = 0; i < e.ia; i++) {
                uint32_t g = s.groups[i];
                lanes_vray r = group_rays(rays, g, in[g], false, true);
                if (stats) LANES_COUNT(&stats->box_ops, r.live);
                vfloat entry;
                uint32_t m = vm_bits(box_vs_rays(&r, &box, &entry, exit_scale));
                if (!m) continue;
                out[g] = (uint16_t)m;
                live_rays += (uint64_t)__builtin_popcount(m);
                s.groups[i] = s.groups[ie];
                s.groups[ie++] = g;
            }
            go_count = ie;
        }
        if (go_count == 0) continue;

        if (nd->count > 0) {
            if (stats) {
                stats->leaves_visited++;
                stats->leaf_live_rays += live_rays;
            }
            uint32_t range[1] = {go_first};
            packet_leaf(b, nd, opt, rays, ranged ? range : s.groups, go_count, ranged, out, &s,
                        prim, u, v, occluded, stats);
            continue;
        }
        if (stats) {
            stats->nodes_visited++;
            stats->node_live_rays += live_rays;
        }
        const lanes_bvh2_node *c0 = &b->nodes[nd->first], *c1 = &b->nodes[nd->first + 1];
        /* nearer child along the packet direction popped first */
        float d0 = 0.0f, d1 = 0.0f;
        for (int a = 0; a < 3; a++) {
            d0 += dir[a] * (c0->min[a] + c0->max[a]);
            d1 += dir[a] * (c1->min[a] + c1->max[a]);
        }
        uint32_t near = d0 <= d1 ? nd->first : nd->first + 1, far = near == nd->first ? nd->first + 1 : nd->first;
        uint32_t depth = e.depth + 1 < MAX_DEPTH - 1 ? e.depth + 1 : MAX_DEPTH - 2;
        uint32_t first_arg = ranged ? go_first : go_count, last_arg = ranged ? go_first + go_count - 1 : 0;
        stack[sp++] = (packet_entry){far, first_arg, last_arg, depth};
        stack[sp++] = (packet_entry){near, first_arg, last_arg, depth};
    }
}

/* The entry points: each body instantiated with and without counting. */
LANES_KERNELS_PACKET(LANES_KERNEL_ENTRY)
