/* Frustum culling cores shared by the frustum kernels and the packet
 * traversal of one kernel set. Included only by per-ISA files; everything
 * is static inline. See frustum_kernels.c for what the tests guarantee. */
#ifndef LANES_TRACE_FRUSTUM_CORE_H
#define LANES_TRACE_FRUSTUM_CORE_H

#include "trace/kernels/kernel_common.h"

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
    /* "not after", so a NaN (from an infinite box bound) keeps the box */
    return vm_not(vf_gt(entry, exit_));
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
    /* Every test below culls only on an ordered "outside" compare: a NaN,
     * say 0 * inf from a flat slope over an unbounded box, keeps the box. */
    vmask keep = vm_not(vf_lt(vf_add(h_hi, htol), zero));
    h_lo = vf_max(h_lo, zero);
    h_hi = vf_max(h_hi, zero);
    for (int j = 1; j <= 2; j++) {
        int a = (k + j) % 3;
        float ls = f->lo_slope[a], hs = f->hi_slope[a];
        /* largest value of x_a - (lo0 + ls * h) over the box */
        vfloat hl = ls > 0.0f ? h_lo : h_hi;
        vfloat g_lo = vf_sub(hi[a], vf_add(vf_set1(f->lo0[a]), vf_mul(vf_set1(ls), hl)));
        keep = vm_andnot(keep, vf_lt(vf_add(g_lo, plane_tol(hi[a], f->lo0[a], ls, hl)), zero));
        /* largest value of (hi0 + hs * h) - x_a over the box */
        vfloat hh = hs > 0.0f ? h_hi : h_lo;
        vfloat g_hi = vf_sub(vf_add(vf_set1(f->hi0[a]), vf_mul(vf_set1(hs), hh)), lo[a]);
        keep = vm_andnot(keep, vf_lt(vf_add(g_hi, plane_tol(lo[a], f->hi0[a], hs, hh)), zero));
    }
    return keep;
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

#endif
