/* Frustum culling, written once and compiled per instruction set: building
 * the bound of a set of rays (SIMD across rays) and culling boxes and
 * triangles against it (SIMD across primitives). See lanes_frustum in
 * kernels.h for the two representations.
 *
 * Every cull is conservative: a rejected primitive is missed by every ray
 * of the set, even counting rounding. Bounds are widened outward, and a test
 * rejects only when it fails by more than a bound on its own rounding
 * error. The per-ray tests that follow a cull decide the actual hits. */
#include "trace/kernels/frustum_core.h"
#include "trace/kernels/kernel_decls.h"

void LANES_FN(lanes_frustum_build)(const lanes_rays *rays, const uint32_t *idx, size_t n,
                                   lanes_frustum *f)
{
    const vfloat inf = vf_set1(INFINITY), ninf = vf_set1(-INFINITY), zero = vf_zero();
    vfloat omin[3], omax[3], dmin[3], dmax[3], rmin[3], rmax[3];
    vfloat tnear = inf, tfar = ninf, big = zero;
    vmask any_live = vm_false();
    for (int a = 0; a < 3; a++) {
        omin[a] = dmin[a] = rmin[a] = inf;
        omax[a] = dmax[a] = rmax[a] = ninf;
    }
    memset(f, 0, sizeof *f);

    /* Pass 1: ranges of origins, directions, reciprocals and t, over the
     * active rays only (inactive lanes hold +inf/-inf in the reductions). */
    for (size_t i = 0; i < n; i += LANES_W) {
        lanes_vray r = lanes_load_rays(rays, idx, i, n, true, true);
        vmask act = vm_and(r.live, vf_le(r.tnear, r.tfar));
        any_live = vm_or(any_live, act);
        vfloat o[3] = {r.ox, r.oy, r.oz}, d[3] = {r.dx, r.dy, r.dz}, rd[3] = {r.rdx, r.rdy, r.rdz};
        for (int a = 0; a < 3; a++) {
            omin[a] = vf_min(vf_select(act, o[a], inf), omin[a]);
            omax[a] = vf_max(vf_select(act, o[a], ninf), omax[a]);
            dmin[a] = vf_min(vf_select(act, d[a], inf), dmin[a]);
            dmax[a] = vf_max(vf_select(act, d[a], ninf), dmax[a]);
            rmin[a] = vf_min(vf_select(act, rd[a], inf), rmin[a]);
            rmax[a] = vf_max(vf_select(act, rd[a], ninf), rmax[a]);
            big = vf_max(vf_select(act, vf_abs(o[a]), zero), big);
        }
        tnear = vf_min(vf_select(act, r.tnear, inf), tnear);
        tfar = vf_max(vf_select(act, r.tfar, ninf), tfar);
    }
    if (vm_none(any_live)) {
        f->valid = true;
        f->empty = true;
        return;
    }
    for (int a = 0; a < 3; a++) {
        f->omin[a] = vf_reduce_min(omin[a]);
        f->omax[a] = vf_reduce_max(omax[a]);
        f->dmin[a] = vf_reduce_min(dmin[a]);
        f->dmax[a] = vf_reduce_max(dmax[a]);
        f->rmin[a] = vf_reduce_min(rmin[a]);
        f->rmax[a] = vf_reduce_max(rmax[a]);
    }
    f->tnear = vf_reduce_min(tnear);
    f->tfar = vf_reduce_max(tfar);
    if (!(vf_reduce_max(big) < FRUSTUM_MAX_COORD)) return; /* valid = false: cull nothing */
    f->valid = true;

    /* Interval test set-up: an axis takes part only when every direction
     * has the same strict sign and finite reciprocal. */
    for (int a = 0; a < 3; a++) {
        bool same_sign = f->dmin[a] > 0.0f || f->dmax[a] < 0.0f;
        bool finite = fabsf(f->rmin[a]) < FLT_MAX && fabsf(f->rmax[a]) < FLT_MAX;
        f->ia_axis_ok[a] = same_sign && finite;
    }

    /* Planes: the dominant axis is the one whose smallest |d| is largest
     * among the axes of one sign. */
    int k = -1;
    float best = 0.0f;
    for (int a = 0; a < 3; a++) {
        float m = f->dmin[a] > 0.0f ? f->dmin[a] : (f->dmax[a] < 0.0f ? -f->dmax[a] : 0.0f);
        if (m > best) best = m, k = a;
    }
    /* The planes bound the rays from their origins on; rays that start
     * behind their origin (tnear < 0) would need the start points instead. */
    if (k < 0 || !(f->tnear >= 0.0f)) return;
    f->k = k;
    f->ksign = f->dmin[k] > 0.0f ? 1.0f : -1.0f;
    f->near = f->ksign > 0.0f ? f->omin[k] : f->omax[k];

    /* Pass 2: each ray's crossing of the near plane and its slopes
     * sigma = d[a] / |d[k]| on the other two axes. A point of the ray at
     * h = (x_k - near) * ksign >= 0 has x_a = cross_a + sigma_a * h. */
    int ax[2] = {(k + 1) % 3, (k + 2) % 3};
    vfloat cmin[2] = {inf, inf}, cmax[2] = {ninf, ninf}, smin[2] = {inf, inf}, smax[2] = {ninf, ninf};
    vfloat errmax = zero, steep = zero;
    const vfloat near = vf_set1(f->near), ksign = vf_set1(f->ksign);
    for (size_t i = 0; i < n; i += LANES_W) {
        lanes_vray r = lanes_load_rays(rays, idx, i, n, true, false);
        vmask act = vm_and(r.live, vf_le(r.tnear, r.tfar));
        vfloat o[3] = {r.ox, r.oy, r.oz}, d[3] = {r.dx, r.dy, r.dz};
        vfloat adk = vf_abs(d[k]);
        vfloat back = vf_mul(vf_sub(o[k], near), ksign); /* >= 0: the origin's h */
        for (int j = 0; j < 2; j++) {
            int a = ax[j];
            vfloat sigma = vf_div(d[a], adk);
            vfloat cross = vf_sub(o[a], vf_mul(sigma, back));
            cmin[j] = vf_min(vf_select(act, cross, inf), cmin[j]);
            cmax[j] = vf_max(vf_select(act, cross, ninf), cmax[j]);
            smin[j] = vf_min(vf_select(act, sigma, inf), smin[j]);
            smax[j] = vf_max(vf_select(act, sigma, ninf), smax[j]);
            /* bound on the rounding of cross: a few ulps of its terms */
            vfloat mag = vf_add(vf_abs(o[a]), vf_abs(vf_mul(sigma, back)));
            errmax = vf_max(vf_select(act, mag, zero), errmax);
            steep = vf_max(vf_select(act, vf_abs(sigma), zero), steep);
        }
    }
    /* A dominant axis whose smallest component is tiny against the others
     * (a denormal, say) gives slopes that overflow: no planes then. */
    if (!(vf_reduce_max(steep) < FRUSTUM_MAX_COORD) || !(vf_reduce_max(errmax) < FRUSTUM_MAX_COORD)) return;
    float err = vf_reduce_max(errmax) * (8.0f * LANES_U) + WIDEN_ABS;
    for (int j = 0; j < 2; j++) {
        int a = ax[j];
        float lo_s = vf_reduce_min(smin[j]), hi_s = vf_reduce_max(smax[j]);
        f->lo0[a] = vf_reduce_min(cmin[j]) - err;
        f->hi0[a] = vf_reduce_max(cmax[j]) + err;
        /* the division rounds to 0.5 ulp: widen the slopes by 2 */
        f->lo_slope[a] = lo_s - fabsf(lo_s) * (2.0f * LANES_U);
        f->hi_slope[a] = hi_s + fabsf(hi_s) * (2.0f * LANES_U);
    }
    f->has_planes = true;
}

LANES_BODY size_t frustum_boxes_body(const lanes_frustum *f, const lanes_boxes *b, size_t n,
                                     lanes_cull_method method, uint32_t *keep,
                                     lanes_lane_stats *stats)
{
    size_t kept = 0;
    for (size_t i = 0; i < n; i += LANES_W) {
        vmask live = vm_first_n(n - i);
        vmask m = live;
        if (f->empty) {
            m = vm_false();
        } else if (f->valid) {
            vfloat lo[3] = {vf_load(b->minx + i), vf_load(b->miny + i), vf_load(b->minz + i)};
            vfloat hi[3] = {vf_load(b->maxx + i), vf_load(b->maxy + i), vf_load(b->maxz + i)};
            /* empty boxes (min > max) are never hit */
            m = vm_and(m, vm_and(vf_le(lo[0], hi[0]), vm_and(vf_le(lo[1], hi[1]), vf_le(lo[2], hi[2]))));
            if (method & LANES_CULL_INTERVAL) m = vm_and(m, boxes_interval(f, lo, hi));
            if ((method & LANES_CULL_PLANES) && f->has_planes) m = vm_and(m, boxes_planes(f, lo, hi));
        }
        LANES_COUNT(stats, live);
        lanes_put_bits(keep, i, m);
        kept += (size_t)vm_popcount(m);
    }
    return kept;
}

LANES_BODY size_t frustum_tris_body(const lanes_frustum *f, const lanes_triangles *t, size_t n,
                                    lanes_cull_method method, uint32_t *keep,
                                    lanes_lane_stats *stats)
{
    size_t kept = 0;
    for (size_t i = 0; i < n; i += LANES_W) {
        vmask live = vm_first_n(n - i);
        vmask m = live;
        if (f->empty) {
            m = vm_false();
        } else if (f->valid) {
            vfloat v0[3] = {vf_loadu(t->v0x + i), vf_loadu(t->v0y + i), vf_loadu(t->v0z + i)};
            vfloat v1[3] = {vf_loadu(t->v1x + i), vf_loadu(t->v1y + i), vf_loadu(t->v1z + i)};
            vfloat v2[3] = {vf_loadu(t->v2x + i), vf_loadu(t->v2y + i), vf_loadu(t->v2z + i)};
            if (method & LANES_CULL_INTERVAL) m = vm_and(m, tris_interval(f, v0, v1, v2));
            if ((method & LANES_CULL_PLANES) && f->has_planes) {
                const vfloat *const v[3] = {v0, v1, v2};
                m = vm_and(m, tris_planes(f, v));
            }
        }
        LANES_COUNT(stats, live);
        lanes_put_bits(keep, i, m);
        kept += (size_t)vm_popcount(m);
    }
    return kept;
}

/* The entry points: each body instantiated with and without counting. */
LANES_KERNELS_FRUSTUM(LANES_KERNEL_ENTRY)
