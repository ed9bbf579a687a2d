/* Double-precision references; see reference.h for the margin idea.
 *
 * The box test works on slab distances (b - o) / d in double: b - o of two
 * floats is exact in double unless their exponents are far apart, and one
 * division rounds once, so equal rationals give equal doubles. The triangle
 * test uses the edge functions E_i = d . ((v_j - o) x (v_k - o)) of the
 * three edges (Plücker form): same sign (zero counts as either) means the
 * line meets the triangle; t = ((v0 - o) . n) / (d . n) with n the normal.
 * Neither follows the kernels' formulas (slab selection by the sign of 1/d,
 * Möller–Trumbore's p/q vectors, the sheared 2D frame of the watertight
 * test); the margins, however, are measured against the magnitudes of the
 * expressions each algorithm evaluates, because that is what decides how
 * far its rounding can reach. */
#include "reference.h"

#include <float.h>
#include <math.h>
#include <string.h>

static bool finite3(const float v[3]) { return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]); }

bool ref_ray_valid(const ref_ray *r)
{
    if (!finite3(r->o) || !finite3(r->d)) return false;
    if (isnan(r->tnear) || isnan(r->tfar)) return false;
    return r->d[0] != 0.0f || r->d[1] != 0.0f || r->d[2] != 0.0f;
}

/* Signed distance from a to b (>= 0 iff a <= b), relative to their size,
 * with REF_TINY as the floor below which float values are underflow noise. */
static double rel_gap(double a, double b)
{
    if (a == b) return 0.0;
    if (isinf(a) || isinf(b)) return a < b ? 1.0 : -1.0;
    double s = fmax(fmax(fabs(a), fabs(b)), REF_TINY);
    return (b - a) / s;
}

/* A direction component whose float reciprocal overflows or is subnormal:
 * the kernels then work with 1/d = ±inf or a denormal, and decisions hinge
 * on displacements far below any relative tolerance (d = 1e-40 moves the
 * ray by 1e-40 per unit t). Such cases are ill-conditioned by nature. */
static bool extreme_component(float d)
{
    float a = fabsf(d);
    return a != 0.0f && (a < FLT_MIN || a > 0x1p126f);
}

ref_box_result ref_box(const ref_ray *r, const float lo[3], const float hi[3])
{
    ref_box_result res = {false, NAN, INFINITY};
    if (!ref_ray_valid(r)) return res;
    for (int a = 0; a < 3; a++)
        if (!(lo[a] <= hi[a])) return res; /* empty: never hit, whatever the rounding */
    if (!(r->tnear <= r->tfar)) return res;

    /* Entry candidates tin[] and exit candidates tout[]: slot 0 is the ray's
     * own interval, then one slot per axis that constrains t. exact_*[] marks
     * values a float evaluation also gets exactly: tnear, tfar, and distances
     * to a plane the origin lies on (0 * (1/d) = 0). */
    double tin[4], tout[4];
    bool exact_in[4], exact_out[4];
    int n = 0;
    bool extreme = false;
    tin[n] = r->tnear, tout[n] = r->tfar, exact_in[n] = exact_out[n] = true, n++;
    for (int a = 0; a < 3; a++) {
        double o = r->o[a], d = r->d[a];
        if (d == 0.0) {
            /* parallel to this slab: the origin decides, exactly */
            if (o < lo[a] || o > hi[a]) return res;
            continue;
        }
        extreme = extreme || extreme_component(r->d[a]);
        double t0 = ((double)lo[a] - o) / d, t1 = ((double)hi[a] - o) / d;
        bool x0 = (double)lo[a] == o, x1 = (double)hi[a] == o;
        if (d < 0.0) {
            double t = t0;
            t0 = t1, t1 = t;
            bool x = x0;
            x0 = x1, x1 = x;
        }
        tin[n] = t0, tout[n] = t1, exact_in[n] = x0, exact_out[n] = x1, n++;
    }
    double entry = tin[0], exit_ = tout[0];
    for (int i = 1; i < n; i++) entry = fmax(entry, tin[i]), exit_ = fmin(exit_, tout[i]);
    res.hit = entry <= exit_;
    if (res.hit) res.tentry = entry;

    /* The decision is the conjunction of tin[p] <= tout[q] over all pairs.
     * Pairs from one slot are exact in float too (monotone rounding keeps
     * lo - o <= hi - o), so only cross pairs can be flipped by rounding.
     * A hit is as robust as its tightest pair; a miss as its most violated. */
    double m = res.hit ? INFINITY : 0.0;
    for (int p = 0; p < n; p++) {
        for (int q = 0; q < n; q++) {
            if (p == q) continue;
            bool exact = exact_in[p] && exact_out[q];
            double g = rel_gap(tin[p], tout[q]);
            if (res.hit) {
                if (!exact) m = fmin(m, fabs(g));
            } else if (g < 0.0) {
                m = fmax(m, exact ? INFINITY : -g);
            }
        }
    }
    res.margin = extreme ? 0.0 : m;
    return res;
}

static void cross(const double a[3], const double b[3], double c[3])
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}
static double dot(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* Sum of |terms| of the cross product a x b, per component. */
static void cross_mag(const double a[3], const double b[3], double c[3])
{
    c[0] = fabs(a[1] * b[2]) + fabs(a[2] * b[1]);
    c[1] = fabs(a[2] * b[0]) + fabs(a[0] * b[2]);
    c[2] = fabs(a[0] * b[1]) + fabs(a[1] * b[0]);
}
static double dot_abs(const double a[3], const double b[3])
{
    return fabs(a[0]) * b[0] + fabs(a[1]) * b[1] + fabs(a[2]) * b[2];
}

/* A margin |value| / magnitude, where a zero magnitude means every term is
 * zero, so float gets the value (0) exactly. */
static double ratio(double value, double mag) { return mag == 0.0 ? INFINITY : fabs(value) / mag; }

/* Magnitudes outside this range put float intermediates near underflow or
 * overflow, where relative error bounds stop holding. */
static bool in_float_range(double mag) { return mag == 0.0 || (mag > 1e-36 && mag < 1e36); }

/* What one algorithm evaluates, reduced to the quantities its decision
 * depends on: three barycentric numerators (signed, one sign convention),
 * the determinant and the numerator of t, each with the sum of the absolute
 * values of the terms the algorithm forms (its rounding scale). */
typedef struct {
    double num[3], mag[3];
    double det, mag_det;
    double mag_tnum;
    bool ok_range;
} tri_terms;

static void tri_margin(const tri_terms *q, bool geom_ok, bool hit, double t,
                       double tnear, double tfar, double u, double v, double *margin,
                       double *tscale, double *uscale, double *vscale)
{
    double m[3];
    for (int i = 0; i < 3; i++) m[i] = ratio(q->num[i], q->mag[i]);
    double mdet = ratio(q->det, q->mag_det);
    /* The error of t = tnum / det, as a scale: its distance to a bound over
     * this scale is a margin like the others. */
    double escale = 0.0, m_near = INFINITY, m_far = INFINITY;
    if (geom_ok) {
        double adet = fabs(q->det);
        escale = q->mag_tnum / adet + fabs(t) * (q->mag_det / adet + 1.0);
        if (isfinite(tnear)) m_near = fabs(t - tnear) / escale;
        if (isfinite(tfar)) m_far = fabs(t - tfar) / escale;
        *tscale = escale;
        *uscale = q->mag[1] / adet + fabs(u) * (q->mag_det / adet + 1.0);
        *vscale = q->mag[2] / adet + fabs(v) * (q->mag_det / adet + 1.0);
    }
    double res;
    if (hit) {
        res = fmin(fmin(fmin(m[0], m[1]), fmin(m[2], mdet)), fmin(m_near, m_far));
    } else {
        /* A miss is robust if two numerators have robustly opposite signs,
         * or if t is robustly outside [tnear, tfar]. */
        res = 0.0;
        for (int i = 0; i < 3; i++)
            for (int j = i + 1; j < 3; j++)
                if ((q->num[i] > 0.0 && q->num[j] < 0.0) || (q->num[i] < 0.0 && q->num[j] > 0.0))
                    res = fmax(res, fmin(m[i], m[j]));
        if (geom_ok) {
            /* escale already carries the determinant's conditioning */
            if (t < tnear) res = fmax(res, m_near);
            if (t > tfar) res = fmax(res, m_far);
        }
    }
    *margin = q->ok_range ? res : 0.0;
}

ref_tri_result ref_tri(const ref_ray *r, const float V0[3], const float V1[3], const float V2[3])
{
    ref_tri_result res;
    memset(&res, 0, sizeof res);
    res.t = res.u = res.v = NAN;
    for (int k = 0; k < 2; k++) res.margin[k] = INFINITY;
    if (!ref_ray_valid(r) || !(r->tnear <= r->tfar)) return res;

    double o[3], d[3], a[3][3], e1[3], e2[3], n[3];
    for (int k = 0; k < 3; k++) {
        o[k] = r->o[k], d[k] = r->d[k];
        a[0][k] = (double)V0[k] - o[k];
        a[1][k] = (double)V1[k] - o[k];
        a[2][k] = (double)V2[k] - o[k];
        e1[k] = (double)V1[k] - V0[k];
        e2[k] = (double)V2[k] - V0[k];
    }
    cross(e1, e2, n);
    res.degenerate = n[0] == 0.0 && n[1] == 0.0 && n[2] == 0.0;
    double D = dot(d, n);
    res.parallel = D == 0.0;
    bool geom_ok = !res.degenerate && !res.parallel;

    /* E[i]: the edge opposite vertex i, so E[i] / sum is the weight of v_i. */
    double E[3], c[3];
    cross(a[1], a[2], c), E[0] = dot(d, c);
    cross(a[2], a[0], c), E[1] = dot(d, c);
    cross(a[0], a[1], c), E[2] = dot(d, c);
    bool pos = E[0] > 0.0 || E[1] > 0.0 || E[2] > 0.0;
    bool neg = E[0] < 0.0 || E[1] < 0.0 || E[2] < 0.0;
    bool inside = !(pos && neg);
    double t = NAN;
    if (geom_ok) {
        t = dot(a[0], n) / D;
        double s = E[0] + E[1] + E[2];
        if (s != 0.0) res.u = E[1] / s, res.v = E[2] / s;
    }
    res.t = t;
    res.hit = geom_ok && inside && t >= r->tnear && t <= r->tfar;

    /* Möller–Trumbore forms det = e1 . (d x e2), u-numerator (o - v0) . (d x e2),
     * v-numerator d . ((o - v0) x e1) and t-numerator e2 . ((o - v0) x e1);
     * its numerators are -E[1], -E[2] and the third is det minus both. */
    tri_terms mt;
    {
        double P[3], Q[3], tv[3] = {-a[0][0], -a[0][1], -a[0][2]};
        cross_mag(d, e2, P);
        cross_mag(tv, e1, Q);
        mt.det = D;
        mt.mag_det = dot_abs(e1, P);
        mt.num[1] = E[1], mt.mag[1] = dot_abs(tv, P);
        mt.num[2] = E[2], mt.mag[2] = dot_abs(d, Q);
        mt.num[0] = E[0], mt.mag[0] = mt.mag_det + mt.mag[1] + mt.mag[2];
        mt.mag_tnum = dot_abs(e2, Q);
        mt.ok_range = in_float_range(mt.mag_det) && in_float_range(mt.mag[0]) &&
                      in_float_range(mt.mag_tnum);
    }
    tri_margin(&mt, geom_ok, res.hit, t, r->tnear, r->tfar, res.u, res.v,
               &res.margin[REF_MOLLER], &res.tscale[REF_MOLLER], &res.uscale[REF_MOLLER],
               &res.vscale[REF_MOLLER]);

    /* The watertight test shears the vertices (minus o) so that d becomes +z
     * along its largest axis kz: X = a_kx - Sx a_kz, Y = a_ky - Sy a_kz with
     * |Sx|, |Sy| <= 1, and forms 2D edge functions X_k Y_j - Y_k X_j, which
     * are E / d_kz. T = sum U_i (a_i,kz / d_kz), t = T / det. */
    tri_terms wt;
    {
        int kz = fabs(d[0]) >= fabs(d[1]) ? (fabs(d[0]) >= fabs(d[2]) ? 0 : 2)
                                          : (fabs(d[1]) >= fabs(d[2]) ? 1 : 2);
        int kx = (kz + 1) % 3, ky = (kz + 2) % 3;
        double adz = fabs(d[kz]), sx = fabs(d[kx] / d[kz]), sy = fabs(d[ky] / d[kz]);
        double X[3], Y[3], Z[3];
        for (int i = 0; i < 3; i++) {
            X[i] = fabs(a[i][kx]) + sx * fabs(a[i][kz]);
            Y[i] = fabs(a[i][ky]) + sy * fabs(a[i][kz]);
            Z[i] = fabs(a[i][kz]) / adz;
        }
        double sum_mag = 0.0, tmag = 0.0;
        for (int i = 0; i < 3; i++) {
            int j = (i + 1) % 3, k = (i + 2) % 3;
            wt.num[i] = E[i] / adz;
            wt.mag[i] = X[k] * Y[j] + Y[k] * X[j];
            sum_mag += wt.mag[i];
            tmag += (wt.mag[i] + fabs(wt.num[i])) * Z[i];
        }
        wt.det = D / adz;
        wt.mag_det = sum_mag;
        wt.mag_tnum = tmag;
        wt.ok_range = in_float_range(sum_mag) && in_float_range(tmag);
    }
    tri_margin(&wt, geom_ok, res.hit, t, r->tnear, r->tfar, res.u, res.v,
               &res.margin[REF_WATERTIGHT], &res.tscale[REF_WATERTIGHT],
               &res.uscale[REF_WATERTIGHT], &res.vscale[REF_WATERTIGHT]);
    return res;
}

bool ref_box_hit(const ref_ray *r, const float lo[3], const float hi[3])
{
    if (!ref_ray_valid(r) || !(r->tnear <= r->tfar)) return false;
    double entry = r->tnear, exit_ = r->tfar;
    for (int a = 0; a < 3; a++) {
        if (!(lo[a] <= hi[a])) return false;
        double o = r->o[a], d = r->d[a];
        if (d == 0.0) {
            if (o < lo[a] || o > hi[a]) return false;
            continue;
        }
        double t0 = ((double)lo[a] - o) / d, t1 = ((double)hi[a] - o) / d;
        entry = fmax(entry, fmin(t0, t1));
        exit_ = fmin(exit_, fmax(t0, t1));
    }
    return entry <= exit_;
}

bool ref_tri_hit(const ref_ray *r, const float V0[3], const float V1[3], const float V2[3])
{
    if (!ref_ray_valid(r) || !(r->tnear <= r->tfar)) return false;
    double d[3], a[3][3], e1[3], e2[3], n[3], c[3], E[3];
    for (int k = 0; k < 3; k++) {
        d[k] = r->d[k];
        a[0][k] = (double)V0[k] - r->o[k];
        a[1][k] = (double)V1[k] - r->o[k];
        a[2][k] = (double)V2[k] - r->o[k];
        e1[k] = (double)V1[k] - V0[k];
        e2[k] = (double)V2[k] - V0[k];
    }
    cross(e1, e2, n);
    double D = dot(d, n);
    if ((n[0] == 0.0 && n[1] == 0.0 && n[2] == 0.0) || D == 0.0) return false;
    cross(a[1], a[2], c), E[0] = dot(d, c);
    cross(a[2], a[0], c), E[1] = dot(d, c);
    cross(a[0], a[1], c), E[2] = dot(d, c);
    bool pos = E[0] > 0.0 || E[1] > 0.0 || E[2] > 0.0;
    bool neg = E[0] < 0.0 || E[1] < 0.0 || E[2] < 0.0;
    if (pos && neg) return false;
    double t = dot(a[0], n) / D;
    return t >= r->tnear && t <= r->tfar;
}

static int64_t ordered(float x)
{
    int32_t i;
    memcpy(&i, &x, sizeof i);
    return i < 0 ? -(int64_t)(i & 0x7fffffff) : (int64_t)i;
}

uint32_t ref_ulp_distance(float a, float b)
{
    if (isnan(a) || isnan(b)) return isnan(a) && isnan(b) ? 0u : UINT32_MAX;
    int64_t d = ordered(a) - ordered(b);
    if (d < 0) d = -d;
    return d > (int64_t)UINT32_MAX ? UINT32_MAX : (uint32_t)d;
}
