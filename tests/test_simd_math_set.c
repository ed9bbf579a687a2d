/* simd/vmath.h and simd/vrandom.h at one kernel set (compiled once per set,
 * like test_simd_ops_set.c, which calls it): exp, log, sin and cos against
 * libm in double, within the bounds vmath.h states, with their special
 * values; the counter-based random numbers bit for bit against a plain C
 * copy of the hash, and their uniformity. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "simd/counter_random.h"
#include "simd/isa.h"
#include "simd/simd.h"
#include "simd/vmath.h"
#include "simd/vrandom.h"
#include "test_simd_ops.h"

#define W LANES_W
#define ARGS_PER_FUNCTION (1 << 20)

/* The bounds vmath.h states, per function (exp, log, sin, cos). */
static const double bound_ulps[] = {1.5, 1.5, 2.0, 2.0};
#define SIN_SMALL 0x1p-6    /* below: an absolute bound instead */
#define SIN_ABS_BOUND 0x1p-30

typedef struct {
    uint64_t s;
} rng;
static uint64_t next(rng *r)
{
    uint64_t z = (r->s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}
static double uniform(rng *r) { return (double)(next(r) >> 11) * 0x1p-53; }
static float in_range(rng *r, double lo, double hi) { return (float)(lo + (hi - lo) * uniform(r)); }
/* |x| from 2^lo to 2^hi, evenly in the exponent, either sign. */
static float log_uniform(rng *r, int lo, int hi)
{
    float x = (float)exp2(lo + (hi - lo) * uniform(r));
    return (next(r) & 1) ? -x : x;
}

static uint32_t fbits(float x)
{
    uint32_t u;
    memcpy(&u, &x, sizeof u);
    return u;
}

/* The float ulp at the exact value y (subnormal spacing below 2^-126). */
static double ulp_at(double y)
{
    int e;
    frexp(y, &e);
    return ldexp(1.0, (e - 1 < -126 ? -126 : e - 1) - 23);
}

typedef enum { F_EXP, F_LOG, F_SIN, F_COS } fn_id;
static const char *const fn_names[] = {"exp", "log", "sin", "cos"};

static vfloat apply(fn_id f, vfloat x)
{
    switch (f) {
    case F_EXP: return vf_exp(x);
    case F_LOG: return vf_log(x);
    case F_SIN: return vf_sin(x);
    default: return vf_cos(x);
    }
}
static double reference(fn_id f, double x)
{
    switch (f) {
    case F_EXP: return exp(x);
    case F_LOG: return log(x);
    case F_SIN: return sin(x);
    default: return cos(x);
    }
}

static float argument(fn_id f, rng *r, int k)
{
    switch (f) {
    case F_EXP:
        return k % 4 == 0 ? log_uniform(r, -30, 0) : in_range(r, -87.3, 88.7);
    case F_LOG: {
        if (k % 4 == 0) return 1.0f + log_uniform(r, -24, -2); /* near 1 */
        uint32_t u = 1u + (uint32_t)(next(r) % 0x7f7fffffu); /* any positive finite, subnormals too */
        float x;
        memcpy(&x, &u, sizeof x);
        return x;
    }
    default:
        if (k % 4 == 0) return log_uniform(r, -30, 0);
        if (k % 4 == 1) return in_range(r, -6.283185307179586, 6.283185307179586);
        return in_range(r, -8192.0, 8192.0);
    }
}

/* The result of one function within its bound: in ulps, or for sin and
 * cos near their zeros, absolutely. */
static bool within(fn_id f, float got, double want, double *ulps)
{
    if (f == F_EXP && fabs(want) < 0x1p-126) { /* subnormal results: half an ulp of 2^-149 each way */
        *ulps = 0.0;
        return fabs(got - want) <= 0x1p-149;
    }
    *ulps = fabs((double)got - want) / ulp_at(want);
    if (*ulps <= bound_ulps[f]) return true;
    return (f == F_SIN || f == F_COS) && fabs(want) < SIN_SMALL && fabs((double)got - want) <= SIN_ABS_BOUND;
}

static void test_function(simd_ctx *c, rng *r, fn_id f)
{
    char name[64];
    snprintf(name, sizeof name, "vmath %s (bound: %.1f ulp)", fn_names[f], bound_ulps[f]);
    simd_begin(c, name);
    double worst = 0.0, worst_abs = 0.0;
    float worst_x = 0.0f;
    for (int k = 0; k < ARGS_PER_FUNCTION / W; k++) {
        float x[W], y[W];
        for (int i = 0; i < W; i++) x[i] = argument(f, r, k);
        vf_storeu(y, apply(f, vf_loadu(x)));
        for (int i = 0; i < W; i++) {
            double want = reference(f, (double)x[i]), ulps;
            if (!within(f, y[i], want, &ulps))
                simd_fail(c, "%s(%a) = %a, libm %a: %.2f ulp", fn_names[f], (double)x[i], (double)y[i], want, ulps);
            if (ulps > worst && !((f == F_SIN || f == F_COS) && fabs(want) < SIN_SMALL)) worst = ulps, worst_x = x[i];
            if ((f == F_SIN || f == F_COS) && ulps > bound_ulps[f] && fabs(y[i] - want) > worst_abs)
                worst_abs = fabs(y[i] - want);
        }
    }
    printf("  %s: worst %.3f ulp at %a", fn_names[f], worst, (double)worst_x);
    if (f == F_SIN || f == F_COS) printf("; beyond it (results below 2^-6), worst %.2g absolute", worst_abs);
    printf("\n");
    simd_end(c);
}

typedef struct {
    float x;
    fn_id f;
    float want; /* NaN: any NaN */
} special_case;

static void test_specials(simd_ctx *c)
{
    simd_begin(c, "vmath special values");
    const special_case cases[] = {
        {NAN, F_EXP, NAN},      {INFINITY, F_EXP, INFINITY}, {-INFINITY, F_EXP, 0.0f},
        {0.0f, F_EXP, 1.0f},    {-0.0f, F_EXP, 1.0f},        {89.0f, F_EXP, INFINITY},
        {1000.0f, F_EXP, INFINITY}, {-1000.0f, F_EXP, 0.0f}, {-FLT_MAX, F_EXP, 0.0f},
        {NAN, F_LOG, NAN},      {INFINITY, F_LOG, INFINITY}, {-INFINITY, F_LOG, NAN},
        {0.0f, F_LOG, -INFINITY}, {-0.0f, F_LOG, -INFINITY}, {-1.0f, F_LOG, NAN},
        {-0x1p-149f, F_LOG, NAN}, {1.0f, F_LOG, 0.0f},
        {NAN, F_SIN, NAN},      {INFINITY, F_SIN, NAN},      {-INFINITY, F_SIN, NAN},
        {0.0f, F_SIN, 0.0f},    {-0.0f, F_SIN, -0.0f},
        {NAN, F_COS, NAN},      {INFINITY, F_COS, NAN},      {-INFINITY, F_COS, NAN},
        {0.0f, F_COS, 1.0f},    {-0.0f, F_COS, 1.0f},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        const special_case *s = &cases[k];
        float got = vf_lane(apply(s->f, vf_set1(s->x)), W - 1);
        bool ok = s->want != s->want ? got != got : fbits(got) == fbits(s->want);
        if (!ok) simd_fail(c, "%s(%a) = %a, expected %a", fn_names[s->f], (double)s->x, (double)got, (double)s->want);
    }
    /* the extremes of the subnormal range through log, and exp's subnormal results */
    for (float x = 0x1p-149f; x < 0x1p-120f; x *= 3.0f) {
        double ulps, want = log((double)x);
        float got = vf_lane(vf_log(vf_set1(x)), 0);
        if (!within(F_LOG, got, want, &ulps)) simd_fail(c, "log(%a) = %a, libm %a", (double)x, (double)got, want);
    }
    for (float x = -103.0f; x < -87.0f; x += 0.37f) {
        double ulps, want = exp((double)x);
        float got = vf_lane(vf_exp(vf_set1(x)), 0);
        if (!within(F_EXP, got, want, &ulps)) simd_fail(c, "exp(%a) = %a, libm %a", (double)x, (double)got, want);
    }
    simd_end(c);
}

/* ---- random numbers ---------------------------------------------------- */

static void test_random(simd_ctx *c, rng *r)
{
    simd_begin(c, "vrandom: bits and floats equal plain C at every lane");
    for (int k = 0; k < 20000; k++) {
        int32_t p[W], s[W], d[W], m[W], bits[W];
        float u[W];
        for (int i = 0; i < W; i++)
            p[i] = (int32_t)next(r), s[i] = (int32_t)(next(r) % 4096), d[i] = (int32_t)(next(r) % 33),
            m[i] = (int32_t)(next(r) % 64);
        vint vp = vi_loadu(p), vs = vi_loadu(s), vd = vi_loadu(d), vm = vi_loadu(m);
        vi_storeu(bits, vi_random_bits(vp, vs, vd, vm));
        vf_storeu(u, vf_random(vp, vs, vd, vm));
        for (int i = 0; i < W; i++) {
            uint32_t want = lanes_random_bits((uint32_t)p[i], (uint32_t)s[i], (uint32_t)d[i], (uint32_t)m[i]);
            float want_u = (float)(want >> 8) * 0x1p-24f;
            if ((uint32_t)bits[i] != want) simd_fail(c, "random_bits lane %d = 0x%08x, expected 0x%08x", i, (uint32_t)bits[i], want);
            if (fbits(u[i]) != fbits(want_u)) simd_fail(c, "random lane %d = %a, expected %a", i, (double)u[i], (double)want_u);
            if (!(u[i] >= 0.0f && u[i] < 1.0f)) simd_fail(c, "random lane %d = %a, outside [0, 1)", i, (double)u[i]);
        }
    }
    simd_end(c);

    /* Consecutive counters (neighbouring pixels; successive dimensions of
     * one path) into 64 bins: chi-square with 63 degrees of freedom has
     * mean 63 and deviation 11.2; 140 is about 7 deviations out. */
    simd_begin(c, "vrandom: uniform over consecutive pixels and dimensions");
    for (int which = 0; which < 2; which++) {
        enum { BINS = 64, N = 1 << 18 };
        long hist[BINS] = {0};
        for (int k = 0; k < N; k += W) {
            vint idx = vi_add(vi_iota(), vi_set1(k));
            vint zero = vi_zero();
            vfloat u = which == 0 ? vf_random(idx, zero, zero, zero) : vf_random(vi_set1(12345), vi_set1(7), vi_set1(3), idx);
            float v[W];
            vf_storeu(v, u);
            for (int i = 0; i < W; i++) hist[(int)(v[i] * BINS)]++;
        }
        double chi2 = 0.0, e = (double)N / BINS;
        for (int b = 0; b < BINS; b++) chi2 += ((double)hist[b] - e) * ((double)hist[b] - e) / e;
        if (chi2 > 140.0) simd_fail(c, "chi-square over consecutive %s: %.1f (63 expected)", which ? "dimensions" : "pixels", chi2);
    }
    simd_end(c);
}

void LANES_FN(test_simd_math_run)(simd_ctx *c)
{
    rng r = {c->seed ^ 0x5eedu ^ (uint64_t)W};
    test_specials(c);
    for (int f = F_EXP; f <= F_COS; f++) test_function(c, &r, (fn_id)f);
    test_random(c, &r);
}
