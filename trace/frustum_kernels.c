/* Frustum culling, written once and compiled per instruction set: building
 * the bound of a set of rays (SIMD across rays) and culling boxes and
 * triangles against it (SIMD across primitives). See lanes_frustum in
 * kernels.h for the two representations.
 *
 * Every cull is conservative: a rejected primitive is missed by every ray
 * of the set, even counting rounding. Bounds are widened outward, and a test
 * rejects only when it fails by more than a bound on its own rounding
 * error. The per-ray tests that follow a cull decide the actual hits. */
#include "trace/kernel_common.h"
#include "trace/kernel_decls.h"

#include <float.h>

/* Rays beyond this size make products overflow; such frusta cull nothing. */
#define FRUSTUM_MAX_COORD 1e18f
/* Relative widening per interval operation: 4 units of roundoff covers one
 * rounding of the operation plus the error of the stored reciprocal. */
#define WIDEN (4.0f * LANES_U)
/* Absolute widening, for results near the underflow range. */
#define WIDEN_ABS 1e-30f

static inline float widen_down(float x) { return x - fabsf(x) * WIDEN - WIDEN_ABS; }
static inline float widen_up(float x) { return x + fabsf(x) * WIDEN + WIDEN_ABS; }

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
    vfloat errmax = zero;
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
        }
    }
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

/* Interval products: [a_lo, a_hi] * [b_lo, b_hi], widened outward. */
typedef struct {
    vfloat lo, hi;
} vinterval;

LANES_BODY vinterval iv_widen(vfloat lo, vfloat hi)
{
    const vfloat rel = vf_set1(WIDEN), abs_ = vf_set1(WIDEN_ABS);
    vinterval r;
    r.lo = vf_sub(vf_sub(lo, vf_mul(vf_abs(lo), rel)), abs_);
    r.hi = vf_add(vf_add(hi, vf_mul(vf_abs(hi), rel)), abs_);
    return r;
}

LANES_BODY vinterval iv_mul(vinterval a, vinterval b)
{
    vfloat p1 = vf_mul(a.lo, b.lo), p2 = vf_mul(a.lo, b.hi);
    vfloat p3 = vf_mul(a.hi, b.lo), p4 = vf_mul(a.hi, b.hi);
    return iv_widen(vf_min(vf_min(p1, p2), vf_min(p3, p4)), vf_max(vf_max(p1, p2), vf_max(p3, p4)));
}

LANES_BODY vinterval iv_add(vinterval a, vinterval b)
{
    return iv_widen(vf_add(a.lo, b.lo), vf_add(a.hi, b.hi));
}

LANES_BODY vinterval iv_sub(vinterval a, vinterval b)
{
    return iv_widen(vf_sub(a.lo, b.hi), vf_sub(a.hi, b.lo));
}

LANES_BODY vinterval iv_point(vfloat x) { return (vinterval){x, x}; }
LANES_BODY vinterval iv_const(float lo, float hi) { return (vinterval){vf_set1(lo), vf_set1(hi)}; }

/* Reshetov's slab-interval test: over all rays, the latest possible entry
 * into one slab must not come after the earliest possible exit from another
 * (Wu 2016, 2.2.1). Returns the lanes that may be hit. */
LANES_BODY vmask boxes_interval(const lanes_frustum *f, const vfloat lo[3], const vfloat hi[3])
{
    vfloat entry = vf_set1(widen_down(f->tnear)), exit_ = vf_set1(widen_up(f->tfar));
    for (int a = 0; a < 3; a++) {
        if (!f->ia_axis_ok[a]) continue;
        vinterval o = iv_const(f->omin[a], f->omax[a]);
        vinterval r = iv_const(f->rmin[a], f->rmax[a]);
        /* the near face is min for d > 0, max for d < 0 (same sign for all) */
        vinterval t_near = iv_mul(iv_sub(iv_point(f->rmin[a] > 0.0f ? lo[a] : hi[a]), o), r);
        vinterval t_far = iv_mul(iv_sub(iv_point(f->rmin[a] > 0.0f ? hi[a] : lo[a]), o), r);
        entry = vf_max(t_near.lo, entry);
        exit_ = vf_min(t_far.hi, exit_);
    }
    return vf_le(entry, exit_);
}

/* Rounding bound of the plane function x_a - (c + s * h), for the test. */
LANES_BODY vfloat plane_tol(vfloat xa, float c, float s, vfloat h)
{
    vfloat mag = vf_add(vf_add(vf_abs(xa), vf_set1(fabsf(c))), vf_abs(vf_mul(vf_set1(s), h)));
    return vf_add(vf_mul(mag, vf_set1(8.0f * LANES_U)), vf_set1(WIDEN_ABS));
}

/* Box against the bounding planes: rejected when the whole box (beyond the
 * near plane) is outside one of them. */
LANES_BODY vmask boxes_planes(const lanes_frustum *f, const vfloat lo[3], const vfloat hi[3])
{
    int k = f->k;
    vfloat near = vf_set1(f->near), zero = vf_zero();
    /* h range of the box along the dominant axis */
    vfloat h_lo = f->ksign > 0.0f ? vf_sub(lo[k], near) : vf_sub(near, hi[k]);
    vfloat h_hi = f->ksign > 0.0f ? vf_sub(hi[k], near) : vf_sub(near, lo[k]);
    vfloat htol = vf_add(vf_mul(vf_add(vf_abs(hi[k]), vf_abs(lo[k])), vf_set1(4.0f * LANES_U)),
                         vf_add(vf_set1(fabsf(f->near) * 4.0f * LANES_U), vf_set1(WIDEN_ABS)));
    vmask keep = vf_ge(vf_add(h_hi, htol), zero);
    h_lo = vf_max(h_lo, zero);
    h_hi = vf_max(h_hi, zero);
    for (int j = 1; j <= 2; j++) {
        int a = (k + j) % 3;
        float ls = f->lo_slope[a], hs = f->hi_slope[a];
        /* largest value of x_a - (lo0 + ls * h) over the box */
        vfloat hl = ls > 0.0f ? h_lo : h_hi;
        vfloat g_lo = vf_sub(hi[a], vf_add(vf_set1(f->lo0[a]), vf_mul(vf_set1(ls), hl)));
        keep = vm_and(keep, vf_ge(vf_add(g_lo, plane_tol(hi[a], f->lo0[a], ls, hl)), zero));
        /* largest value of (hi0 + hs * h) - x_a over the box */
        vfloat hh = hs > 0.0f ? h_hi : h_lo;
        vfloat g_hi = vf_sub(vf_add(vf_set1(f->hi0[a]), vf_mul(vf_set1(hs), hh)), lo[a]);
        keep = vm_and(keep, vf_ge(vf_add(g_hi, plane_tol(lo[a], f->hi0[a], hs, hh)), zero));
    }
    return keep;
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

size_t LANES_FN(lanes_frustum_boxes)(const lanes_frustum *f, const lanes_boxes *boxes, size_t n,
                                     lanes_cull_method method, uint32_t *keep,
                                     lanes_lane_stats *stats)
{
    return stats ? frustum_boxes_body(f, boxes, n, method, keep, stats)
                 : frustum_boxes_body(f, boxes, n, method, keep, NULL);
}

/* Boulos et al. (2006) interval arithmetic on the edge functions
 * E_ij = d . ((v_i - o) x (v_j - o)). A ray's line meets the triangle only if
 * the three have one sign (zero counts as either); when one E is positive
 * for every ray of the frustum and another negative for every ray, no ray
 * meets it. Lines, not rays: conservative for t as well. */
LANES_BODY vinterval edge_interval(const lanes_frustum *f, const vfloat vi[3], const vfloat vj[3])
{
    vinterval a[3], b[3], c[3], d[3];
    for (int x = 0; x < 3; x++) {
        vinterval o = iv_const(f->omin[x], f->omax[x]);
        a[x] = iv_sub(iv_point(vi[x]), o);
        b[x] = iv_sub(iv_point(vj[x]), o);
        d[x] = iv_const(f->dmin[x], f->dmax[x]);
    }
    c[0] = iv_sub(iv_mul(a[1], b[2]), iv_mul(a[2], b[1]));
    c[1] = iv_sub(iv_mul(a[2], b[0]), iv_mul(a[0], b[2]));
    c[2] = iv_sub(iv_mul(a[0], b[1]), iv_mul(a[1], b[0]));
    return iv_add(iv_add(iv_mul(d[0], c[0]), iv_mul(d[1], c[1])), iv_mul(d[2], c[2]));
}

LANES_BODY vmask tris_interval(const lanes_frustum *f, const vfloat v0[3], const vfloat v1[3],
                               const vfloat v2[3])
{
    vinterval e01 = edge_interval(f, v0, v1);
    vinterval e12 = edge_interval(f, v1, v2);
    vinterval e20 = edge_interval(f, v2, v0);
    const vfloat zero = vf_zero();
    vmask pos = vm_or(vf_gt(e01.lo, zero), vm_or(vf_gt(e12.lo, zero), vf_gt(e20.lo, zero)));
    vmask neg = vm_or(vf_lt(e01.hi, zero), vm_or(vf_lt(e12.hi, zero), vf_lt(e20.hi, zero)));
    return vm_not(vm_and(pos, neg));
}

/* Reshetov's vertex culling: rejected when all three vertices are outside
 * one bounding plane, or all behind the near plane. A plane function is
 * linear, so outside at the vertices means outside everywhere on the
 * triangle. */
LANES_BODY vmask tris_planes(const lanes_frustum *f, const vfloat *const v[3])
{
    int k = f->k;
    const vfloat zero = vf_zero(), near = vf_set1(f->near), ks = vf_set1(f->ksign);
    vfloat h[3];
    vmask behind = vm_true();
    for (int i = 0; i < 3; i++) {
        h[i] = vf_mul(vf_sub(v[i][k], near), ks);
        vfloat tol = vf_add(vf_mul(vf_add(vf_abs(v[i][k]), vf_abs(near)), vf_set1(4.0f * LANES_U)),
                            vf_set1(WIDEN_ABS));
        behind = vm_and(behind, vf_lt(vf_add(h[i], tol), zero));
    }
    vmask out_any = behind;
    for (int j = 1; j <= 2; j++) {
        int a = (k + j) % 3;
        vmask out_lo = vm_true(), out_hi = vm_true();
        for (int i = 0; i < 3; i++) {
            vfloat xa = v[i][a];
            vfloat g_lo = vf_sub(xa, vf_add(vf_set1(f->lo0[a]), vf_mul(vf_set1(f->lo_slope[a]), h[i])));
            vfloat g_hi = vf_sub(vf_add(vf_set1(f->hi0[a]), vf_mul(vf_set1(f->hi_slope[a]), h[i])), xa);
            out_lo = vm_and(out_lo, vf_lt(vf_add(g_lo, plane_tol(xa, f->lo0[a], f->lo_slope[a], h[i])), zero));
            out_hi = vm_and(out_hi, vf_lt(vf_add(g_hi, plane_tol(xa, f->hi0[a], f->hi_slope[a], h[i])), zero));
        }
        out_any = vm_or(out_any, vm_or(out_lo, out_hi));
    }
    return vm_not(out_any);
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
            vfloat v0[3] = {vf_load(t->v0x + i), vf_load(t->v0y + i), vf_load(t->v0z + i)};
            vfloat v1[3] = {vf_load(t->v1x + i), vf_load(t->v1y + i), vf_load(t->v1z + i)};
            vfloat v2[3] = {vf_load(t->v2x + i), vf_load(t->v2y + i), vf_load(t->v2z + i)};
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

size_t LANES_FN(lanes_frustum_tris)(const lanes_frustum *f, const lanes_triangles *tris, size_t n,
                                    lanes_cull_method method, uint32_t *keep,
                                    lanes_lane_stats *stats)
{
    return stats ? frustum_tris_body(f, tris, n, method, keep, stats)
                 : frustum_tris_body(f, tris, n, method, keep, NULL);
}
