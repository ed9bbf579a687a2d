/* exp, log, sin and cos on the SIMD layer's vectors, written once against
 * the generic names (simd.h) and so compiled at every width: the shaders'
 * transcendental functions, which no set has in hardware. Each reduces its
 * argument to a small interval and evaluates a polynomial there, with
 * coefficients fitted for this code (near-minimax in the relative error,
 * by Lawson's iteration on the interval; their own error is at most 6e-9
 * relative, a tenth of a float ulp).
 *
 * Error bounds, against libm in double (tests/test_simd_math_set.c checks
 * them at every set on 2^20 arguments per function, and the special
 * values; the worst it found is in brackets):
 *   vf_exp  1.5 ulp [0.98] for x in [-87.3, 88.7] (normal results); below,
 *           a subnormal within one subnormal step, or 0; above, +inf.
 *   vf_log  1.5 ulp [0.79] for x > 0, subnormals included. 0 -> -inf,
 *           +inf -> +inf, x < 0 -> NaN.
 *   vf_sin, vf_cos  2 ulp [1.57] for |x| <= 8192, or 2^-30 absolute
 *           [1.7e-10] where the result is below 2^-6: near a zero, the
 *           reduced argument's own error (the third part of pi/2 rounded,
 *           times j) is no longer small against the result. Beyond 8192
 *           the result stays in [-1, 1] but its error grows with |x|.
 *           +-inf -> NaN.
 * NaN in gives NaN out. Without FMA (scalar, sse4, avx) vf_fmadd rounds
 * twice, so those sets round differently from the FMA sets but keep the
 * same bounds.
 *
 * Included by per-ISA files; everything is static inline. */
#ifndef LANES_SIMD_VMATH_H
#define LANES_SIMD_VMATH_H

#include <math.h>

#include "simd.h"

/* ln 2 = LANES_LN2_HI + LANES_LN2_LO, the first with 9 significant bits so
 * that n * LANES_LN2_HI is exact for every |n| < 2^15. */
#define LANES_LN2_HI 0.693359375f
#define LANES_LN2_LO -2.12194440e-4f

/* pi/2 in three parts of 8, 7 and 24 bits (Cody and Waite): j * the first
 * two is exact for |j| < 2^16, so the reduced argument loses only the
 * third's rounding. */
#define LANES_PIO2_1 1.5703125f
#define LANES_PIO2_2 4.84466552734375e-4f
#define LANES_PIO2_3 -6.39757843e-7f

/* e^x = 2^n e^r, r = x - n ln 2 in [-ln2/2, ln2/2]; e^r = 1 + r + r^2 P(r).
 * 2^n is applied in two halves so that n down to -159 and up to 129 (the
 * clamp) needs no subnormal or infinite scale factor. */
static inline vfloat vf_exp(vfloat x)
{
    vfloat xc = vf_min(vf_max(x, vf_set1(-110.0f)), vf_set1(89.0f));
    vfloat n = vf_floor(vf_fmadd(xc, vf_set1(1.44269504f), vf_set1(0.5f)));
    vfloat r = vf_fnmadd(n, vf_set1(LANES_LN2_HI), xc);
    r = vf_fnmadd(n, vf_set1(LANES_LN2_LO), r);
    vfloat p = vf_set1(1.97904650e-4f);
    p = vf_fmadd(p, r, vf_set1(1.39446533e-3f));
    p = vf_fmadd(p, r, vf_set1(8.33349675e-3f));
    p = vf_fmadd(p, r, vf_set1(4.16662954e-2f));
    p = vf_fmadd(p, r, vf_set1(1.66666657e-1f));
    p = vf_fmadd(p, r, vf_set1(0.5f));
    vfloat er = vf_add(vf_fmadd(vf_mul(r, r), p, r), vf_set1(1.0f));
    vfloat n1 = vf_floor(vf_mul(n, vf_set1(0.5f))), n2 = vf_sub(n, n1);
    vfloat s1 = vi_as_vf(vi_sll(vi_add(vf_to_vi(n1), vi_set1(127)), 23));
    vfloat s2 = vi_as_vf(vi_sll(vi_add(vf_to_vi(n2), vi_set1(127)), 23));
    vfloat y = vf_mul(vf_mul(er, s1), s2);
    return vf_select(vf_isnan(x), vf_add(x, x), y);
}

/* log x = e ln 2 + log(1 + f), 1 + f = m in [sqrt(1/2), sqrt(2)), f exact:
 * f - f^2/2 + f^3 P(f), small terms first. (The atanh form, 2s + s^3 L(s^2)
 * with s = f / (2 + f), needs fewer terms but rounds 2 + f and the
 * division: up to 1.97 ulp near 1, against 1 ulp here.) Subnormals are
 * scaled by 2^23 first. */
static inline vfloat vf_log(vfloat x)
{
    vmask tiny = vf_lt(x, vf_set1(0x1p-126f));
    vfloat xs = vf_select(tiny, vf_mul(x, vf_set1(0x1p23f)), x);
    /* Adding 1 - sqrt(1/2) in the bits carries into the exponent exactly
     * when the mantissa is at least sqrt(2)/2 * 2: e and m in one step. */
    vint bits = vi_add(vf_as_vi(xs), vi_set1(0x3f800000 - 0x3f3504f3));
    vfloat e = vi_to_vf(vi_sub(vi_srl(bits, 23), vi_set1(127)));
    e = vf_sub(e, vf_select(tiny, vf_set1(23.0f), vf_zero()));
    vfloat m = vi_as_vf(vi_add(vi_and(bits, vi_set1(0x007fffff)), vi_set1(0x3f3504f3)));
    vfloat f = vf_sub(m, vf_set1(1.0f)), z = vf_mul(f, f);
    vfloat p = vf_set1(-7.63422400e-2f);
    p = vf_fmadd(p, f, vf_set1(1.27614677e-1f));
    p = vf_fmadd(p, f, vf_set1(-1.31602347e-1f));
    p = vf_fmadd(p, f, vf_set1(1.42017767e-1f));
    p = vf_fmadd(p, f, vf_set1(-1.66233540e-1f));
    p = vf_fmadd(p, f, vf_set1(2.00012267e-1f));
    p = vf_fmadd(p, f, vf_set1(-2.50008225e-1f));
    p = vf_fmadd(p, f, vf_set1(3.33333313e-1f));
    vfloat t = vf_fmadd(vf_mul(f, z), p, vf_mul(e, vf_set1(LANES_LN2_LO)));
    t = vf_fnmadd(z, vf_set1(0.5f), t);
    vfloat y = vf_fmadd(e, vf_set1(LANES_LN2_HI), vf_add(f, t));
    y = vf_select(vf_eq(x, vf_set1(INFINITY)), x, y);
    y = vf_select(vf_eq(x, vf_zero()), vf_set1(-INFINITY), y);
    y = vf_select(vf_lt(x, vf_zero()), vf_set1(NAN), y);
    return vf_select(vf_isnan(x), vf_add(x, x), y);
}

/* sin (quarter = 0) or cos (quarter = 1) of x = j pi/2 + r, |r| <= pi/4:
 * the sine or cosine polynomial of r by the quadrant j + quarter. */
static inline vfloat vf_sin_quadrant_(vfloat x, int quarter)
{
    vfloat j = vf_floor(vf_fmadd(x, vf_set1(0.636619772f), vf_set1(0.5f)));
    vfloat r = vf_fnmadd(j, vf_set1(LANES_PIO2_1), x);
    r = vf_fnmadd(j, vf_set1(LANES_PIO2_2), r);
    r = vf_fnmadd(j, vf_set1(LANES_PIO2_3), r);
    vfloat z = vf_mul(r, r);
    vfloat ps = vf_set1(-1.95152796e-4f);
    ps = vf_fmadd(ps, z, vf_set1(8.33216030e-3f));
    ps = vf_fmadd(ps, z, vf_set1(-1.66666552e-1f));
    vfloat sin_r = vf_fmadd(vf_mul(r, z), ps, r);
    vfloat pc = vf_set1(2.44331495e-5f);
    pc = vf_fmadd(pc, z, vf_set1(-1.38873165e-3f));
    pc = vf_fmadd(pc, z, vf_set1(4.16666456e-2f));
    vfloat cos_r = vf_fmadd(vf_mul(z, z), pc, vf_fnmadd(z, vf_set1(0.5f), vf_set1(1.0f)));
    /* j is integral (or not finite, when the result is NaN anyway), and
     * the quadrant is j mod 4 in two's complement. */
    vint q = vi_add(vf_to_vi(j), vi_set1(quarter));
    vfloat y = vf_select(vi_eq(vi_and(q, vi_set1(1)), vi_set1(1)), cos_r, sin_r);
    return vf_select(vi_eq(vi_and(q, vi_set1(2)), vi_set1(2)), vf_neg(y), y);
}

/* sin(-0) is -0, which the polynomial's last addition (-0 + +0) loses. */
static inline vfloat vf_sin(vfloat x) { return vf_select(vf_eq(x, vf_zero()), x, vf_sin_quadrant_(x, 0)); }
static inline vfloat vf_cos(vfloat x) { return vf_sin_quadrant_(x, 1); }

#endif
