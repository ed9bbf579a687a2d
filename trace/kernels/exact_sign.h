/* The exact sign of a ray's distance to a triangle's plane, for the rare
 * hits where the watertight test's t is too close to 0 for its own sign to
 * be trusted (a shadow ray leaving the surface it starts on). Included only
 * by per-ISA files; everything is static inline (see simd/simd.h).
 *
 * With n = (v1 - v0) x (v2 - v0), the ray o + t d meets the plane at
 * t = n.(v0 - o) / n.d, so sign(t) = sign(n.(v0 - o)) * sign(n.d). Both are
 * 3x3 determinants, which by multilinearity are sums of determinants of the
 * input vectors themselves, i.e. sums of products of three input floats.
 * Such a product is exact as two doubles (x*y is exact in a double; fma
 * gives the error of the second product), and over/underflow is impossible
 * (|x*y*z| lies in [2^-447, 2^384]). The sum of those doubles is kept as a
 * nonoverlapping expansion (Shewchuk 1997, grow-expansion with zero
 * elimination), whose largest component has the sum's sign. A plain double
 * evaluation with a forward error bound decides almost every case first. */
#ifndef LANES_TRACE_EXACT_SIGN_H
#define LANES_TRACE_EXACT_SIGN_H

#include <float.h>
#include <math.h>
#include <stdbool.h>

/* An expansion grows by one component per addition at most, and a sign
 * adds four determinants of six products, two doubles each */
#define EXACT_SIGN_MAX_TERMS 48

typedef struct {
    double e[EXACT_SIGN_MAX_TERMS]; /* the expansion, increasing magnitude */
    int n;
} exact_sum;

/* Adds x exactly: every partial error that is not zero stays a component. */
static inline void exact_sum_add(exact_sum *s, double x)
{
    int kept = 0;
    for (int i = 0; i < s->n; i++) {
        double sum = x + s->e[i];
        double bv = sum - x;
        double err = (x - (sum - bv)) + (s->e[i] - bv);
        if (err != 0.0) s->e[kept++] = err;
        x = sum;
    }
    if (x != 0.0) s->e[kept++] = x;
    s->n = kept;
}

static inline int exact_sum_sign(const exact_sum *s)
{
    if (s->n == 0) return 0;
    return s->e[s->n - 1] > 0.0 ? 1 : -1;
}

/* sign * x*y*z, exactly, as two doubles */
static inline void exact_sum_add_product(exact_sum *s, double sign, float x, float y, float z)
{
    double xy = (double)x * (double)y;
    double p = xy * (double)z;
    double err = fma(xy, (double)z, -p);
    exact_sum_add(s, sign * err);
    exact_sum_add(s, sign * p);
}

/* sign * det[a; b; c] = sign * a.(b x c) */
static inline void exact_sum_add_det(exact_sum *s, double sign, const float a[3], const float b[3],
                                     const float c[3])
{
    exact_sum_add_product(s, sign, a[0], b[1], c[2]);
    exact_sum_add_product(s, -sign, a[0], b[2], c[1]);
    exact_sum_add_product(s, -sign, a[1], b[0], c[2]);
    exact_sum_add_product(s, sign, a[1], b[2], c[0]);
    exact_sum_add_product(s, sign, a[2], b[0], c[1]);
    exact_sum_add_product(s, -sign, a[2], b[1], c[0]);
}

/* det[e1; e2; x] for x = w in double, with a bound on its error: the
 * differences may round once each (a double holds 53 bits, a difference of
 * floats far apart in exponent needs more), each product twice, and the
 * sum of six terms five times, every error relative to the permanent. */
static inline double det_filtered(const double e1[3], const double e2[3], const double x[3],
                                  double *bound)
{
    double c0 = e1[1] * e2[2] - e1[2] * e2[1];
    double c1 = e1[2] * e2[0] - e1[0] * e2[2];
    double c2 = e1[0] * e2[1] - e1[1] * e2[0];
    double p0 = fabs(e1[1] * e2[2]) + fabs(e1[2] * e2[1]);
    double p1 = fabs(e1[2] * e2[0]) + fabs(e1[0] * e2[2]);
    double p2 = fabs(e1[0] * e2[1]) + fabs(e1[1] * e2[0]);
    double permanent = fabs(x[0]) * p0 + fabs(x[1]) * p1 + fabs(x[2]) * p2;
    /* 10 roundings of at most DBL_EPSILON/2 each; 16 leaves room for the
     * rounding of the bound itself */
    *bound = 16.0 * DBL_EPSILON * permanent;
    return x[0] * c0 + x[1] * c1 + x[2] * c2;
}

static inline bool finite3(const float a[3])
{
    return isfinite(a[0]) && isfinite(a[1]) && isfinite(a[2]);
}

/* The sign of the exact n.(v0 - o) and n.d, each -1, 0 or +1. */
static inline void exact_plane_signs(const float v0[3], const float v1[3], const float v2[3],
                                     const float o[3], const float d[3], int *sign_nw, int *sign_nd)
{
    double e1[3], e2[3], w[3], dd[3];
    for (int a = 0; a < 3; a++) {
        e1[a] = (double)v1[a] - (double)v0[a];
        e2[a] = (double)v2[a] - (double)v0[a];
        w[a] = (double)v0[a] - (double)o[a];
        dd[a] = (double)d[a];
    }
    double bound;
    double nw = det_filtered(e1, e2, w, &bound);
    if (fabs(nw) > bound) {
        *sign_nw = nw > 0.0 ? 1 : -1;
    } else {
        /* det[v1-v0; v2-v0; v0-o]: the terms with v0 twice vanish */
        exact_sum s = {.n = 0};
        exact_sum_add_det(&s, 1.0, v1, v2, v0);
        exact_sum_add_det(&s, -1.0, v1, v2, o);
        exact_sum_add_det(&s, 1.0, v1, v0, o);
        exact_sum_add_det(&s, 1.0, v0, v2, o);
        *sign_nw = exact_sum_sign(&s);
    }
    double nd = det_filtered(e1, e2, dd, &bound);
    if (fabs(nd) > bound) {
        *sign_nd = nd > 0.0 ? 1 : -1;
    } else {
        exact_sum s = {.n = 0};
        exact_sum_add_det(&s, 1.0, v1, v2, d);
        exact_sum_add_det(&s, -1.0, v1, v0, d);
        exact_sum_add_det(&s, -1.0, v0, v2, d);
        *sign_nd = exact_sum_sign(&s);
    }
}

/* The sign of the exact t at which the ray o + t d meets the plane of
 * (v0, v1, v2): -1, 0 or +1, or one of these when there is none. */
#define EXACT_T_PARALLEL 2   /* the ray is parallel to the plane: no single t */
#define EXACT_T_NOT_FINITE 3 /* an input is infinite or NaN */

static inline int exact_plane_t_sign(const float v0[3], const float v1[3], const float v2[3],
                                     const float o[3], const float d[3])
{
    if (!finite3(v0) || !finite3(v1) || !finite3(v2) || !finite3(o) || !finite3(d))
        return EXACT_T_NOT_FINITE;
    int sign_nw, sign_nd;
    exact_plane_signs(v0, v1, v2, o, d, &sign_nw, &sign_nd);
    if (sign_nd == 0) return EXACT_T_PARALLEL;
    return sign_nw * sign_nd;
}

/* A computed t moved to the side of 0 the exact t is on; t is kept when it
 * is already there, since only its sign was in doubt. */
static inline float t_on_exact_side(float t, int sign)
{
    if (sign > 0) return t > 0.0f ? t : FLT_TRUE_MIN;
    if (sign < 0) return t < 0.0f ? t : -FLT_TRUE_MIN;
    return 0.0f;
}

#endif
