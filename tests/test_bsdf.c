/* The shaders' BSDFs (trace/kernels/bsdf_core.h) at every kernel set the
 * CPU runs, against the double-precision references of bsdf_reference.c:
 *   - eval and pdf within a stated relative error, on random directions
 *     and parameters, both sides of the surface;
 *   - reciprocity: f(wo, wi) = f(wi, wo); for rough glass's transmission,
 *     which leaves out the radiance scaling, f(wo, wi) eta_o^2 =
 *     f(wi, wo) eta_i^2 (eta_o, eta_i the indices on wo's and wi's sides);
 *   - every sampled direction: unit length, on the right side, its pdf and
 *     weight (f cos / pdf) those of the reference; glass by Snell's law;
 *     an invalid sample has weight and pdf 0;
 *   - the sampler is unbiased: the mean weight equals the reference's
 *     directional albedo (a quadrature), which is at most 1; glass
 *     reflects with the Fresnel probability;
 *   - the sampled directions follow the pdf: a chi-square test over a
 *     grid of (cos theta, phi) bins, the expected counts integrated from
 *     the reference pdf; over the sphere for rough glass;
 *   - rough glass at degenerate directions (in the plane, no microfacet
 *     between them): f, pdf and weights 0, never NaN.
 *
 *   test_bsdf [--isa a,b,...] */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bsdf_reference.h"
#include "harness.h"
#include "simd/isa.h"
#include "trace/kernels.h"

#define PI 3.14159265358979323846

typedef void (*eval_fn)(const lanes_bsdf *, size_t, const float *, const float *, const float *, float *, float *);
typedef void (*sample_fn)(const lanes_bsdf *, size_t, const float *, const float *, const float *, float *, float *,
                          float *, uint8_t *);

/* The stated accuracy of eval, pdf and the sample weights against the
 * reference: relative, with an absolute floor for values near 0. */
#define REL_TOL 2e-4
#define ABS_TOL 1e-6

enum { N = 1 << 14 }; /* directions per batch */

static const char *const kind_names[] = {"lambert", "mirror", "conductor", "plastic", "glass", "rough_glass"};

typedef struct {
    float wo[3 * N], wi[3 * N], u[3 * N], f[3 * N], pdf[N], weight[3 * N];
    uint8_t flags[N];
} batch;

static void random_direction(harness_rng *r, double d[3])
{
    double z = 2.0 * harness_uniform(r) - 1.0, phi = 2.0 * PI * harness_uniform(r), s = sqrt(fmax(0.0, 1.0 - z * z));
    d[0] = s * cos(phi), d[1] = s * sin(phi), d[2] = z;
}

static void put(float *soa, size_t i, const double d[3])
{
    for (int k = 0; k < 3; k++) soa[(size_t)k * N + i] = (float)d[k];
}

static void get(const float *soa, size_t i, double d[3])
{
    for (int k = 0; k < 3; k++) d[k] = soa[(size_t)k * N + i];
}

static lanes_bsdf random_bsdf(harness_rng *r, lanes_bsdf_kind kind)
{
    lanes_bsdf b = {.kind = kind};
    for (int k = 0; k < 3; k++) b.albedo[k] = (float)harness_uniform(r), b.f0[k] = (float)harness_uniform(r);
    b.roughness = (float)(0.05 + 0.95 * harness_uniform(r));
    b.ior = (float)(1.1 + 1.4 * harness_uniform(r));
    /* rough glass: a quarter of them less dense inside (a bubble) */
    if (kind == LANES_BSDF_ROUGH_GLASS && harness_uniform(r) < 0.25) b.ior = 1.0f / b.ior;
    return b;
}

static bool near(double got, double want) { return fabs(got - want) <= REL_TOL * fabs(want) + ABS_TOL; }

static double rel_err(double got, double want) { return fabs(got - want) / fmax(fabs(want), 1e-30); }

/* The index on d's side for rough glass: 1 outside (+z), ior inside. */
static double side_index(const lanes_bsdf *b, const double d[3]) { return d[2] > 0.0 ? 1.0 : (double)b->ior; }

/* wo refracted through the surface (normal +z) into wt; false beyond the
 * critical angle. */
static bool refracted(const lanes_bsdf *b, const double wo[3], double wt[3])
{
    double s = wo[2] > 0.0 ? 1.0 : -1.0, eta = wo[2] > 0.0 ? 1.0 / b->ior : (double)b->ior, c = fabs(wo[2]);
    double k = 1.0 - eta * eta * (1.0 - c * c);
    if (k <= 0.0) return false;
    double ct = sqrt(k);
    wt[0] = -eta * wo[0], wt[1] = -eta * wo[1], wt[2] = -s * ct;
    return true;
}

/* ---- eval, pdf, reciprocity ------------------------------------------- */

static void test_eval(const char *isa, eval_fn eval, batch *bt, harness_rng *r)
{
    for (int kind = 0; kind <= LANES_BSDF_ROUGH_GLASS; kind++) {
        double worst = 0.0, worst_t = 0.0, worst_pdf = 0.0; /* f reflected, transmitted; pdf */
        for (int round = 0; round < 4; round++) {
            lanes_bsdf b = random_bsdf(r, (lanes_bsdf_kind)kind);
            for (size_t i = 0; i < N; i++) {
                double wo[3], wi[3];
                random_direction(r, wo);
                random_direction(r, wi);
                if (i % 2) {
                    /* near the mirror direction, where a sharp lobe peaks;
                     * for rough glass every other one near the refracted */
                    double e = pow(10.0, -4.0 * harness_uniform(r)), peak[3] = {-wo[0], -wo[1], wo[2]};
                    if (kind == LANES_BSDF_ROUGH_GLASS && i % 4 == 3) refracted(&b, wo, peak);
                    for (int k = 0; k < 3; k++) wi[k] = peak[k] + e * wi[k];
                    double len = sqrt(wi[0] * wi[0] + wi[1] * wi[1] + wi[2] * wi[2]);
                    for (int k = 0; k < 3; k++) wi[k] /= len;
                }
                put(bt->wo, i, wo);
                put(bt->wi, i, wi);
            }
            eval(&b, N, NULL, bt->wo, bt->wi, bt->f, bt->pdf);
            for (size_t i = 0; i < N; i++) {
                double wo[3], wi[3], f[3], pdf;
                get(bt->wo, i, wo);
                get(bt->wi, i, wi);
                ref_bsdf_eval(&b, wo, wi, f, &pdf);
                bool ok = near(bt->pdf[i], pdf);
                for (int k = 0; k < 3; k++) ok = ok && near(bt->f[(size_t)k * N + i], f[k]);
                if (!CHECK(ok, "%s %s (roughness %g): f(wo (%g %g %g), wi (%g %g %g)) = %g %g %g pdf %g, reference %g %g %g pdf %g",
                           isa, kind_names[kind], (double)b.roughness, wo[0], wo[1], wo[2], wi[0], wi[1], wi[2],
                           (double)bt->f[i], (double)bt->f[N + i], (double)bt->f[2 * N + i], (double)bt->pdf[i], f[0],
                           f[1], f[2], pdf))
                    continue;
                if (f[0] > 1e-3) {
                    double e = rel_err(bt->f[i], f[0]);
                    if (wo[2] * wi[2] > 0.0)
                        worst = fmax(worst, e);
                    else
                        worst_t = fmax(worst_t, e);
                }
                if (pdf > 1e-3) worst_pdf = fmax(worst_pdf, rel_err(bt->pdf[i], pdf));
            }
            /* reciprocity: the same call with the directions swapped; rough
             * glass's transmission f(wi, wo) = f(wo, wi) eta_o^2 / eta_i^2 */
            memcpy(bt->u, bt->f, sizeof bt->f); /* keep f(wo, wi) */
            eval(&b, N, NULL, bt->wi, bt->wo, bt->f, bt->pdf);
            for (size_t i = 0; i < 3 * N; i++) {
                double wo[3], wi[3], scale = 1.0;
                get(bt->wo, i % N, wo);
                get(bt->wi, i % N, wi);
                if (kind == LANES_BSDF_ROUGH_GLASS && wo[2] * wi[2] < 0.0) {
                    double q = side_index(&b, wo) / side_index(&b, wi);
                    scale = q * q;
                }
                CHECK(near(bt->f[i], scale * bt->u[i]),
                      "%s %s (roughness %g, ior %g): f(wi, wo) = %g, f(wo, wi) = %g (times %g), "
                      "wo (%a %a %a) wi (%a %a %a)",
                      isa, kind_names[kind], (double)b.roughness, (double)b.ior, (double)bt->f[i], (double)bt->u[i],
                      scale, wo[0], wo[1], wo[2], wi[0], wi[1], wi[2]);
            }
        }
        if (kind == LANES_BSDF_ROUGH_GLASS)
            printf("  %s %s: eval worst relative error %.2g reflected, %.2g transmitted, pdf %.2g (stated %.0e)\n", isa,
                   kind_names[kind], worst, worst_t, worst_pdf, REL_TOL);
        else
            printf("  %s %s: eval worst relative error %.2g, pdf %.2g (stated %.0e)\n", isa, kind_names[kind], worst,
                   worst_pdf, REL_TOL);
    }
}

/* ---- samples: each one, and the sampler's mean ------------------------- */

static void sample_batch(sample_fn sample, batch *bt, const lanes_bsdf *b, const double wo[3], harness_rng *r)
{
    for (size_t i = 0; i < N; i++) {
        put(bt->wo, i, wo);
        for (int k = 0; k < 3; k++) bt->u[(size_t)k * N + i] = (float)(harness_next(r) >> 40) * 0x1p-24f;
    }
    sample(b, N, NULL, bt->wo, bt->u, bt->wi, bt->weight, bt->pdf, bt->flags);
}

/* Checks every sample of a batch for wo against the reference. */
static void check_samples(const char *isa, const lanes_bsdf *b, const batch *bt)
{
    for (size_t i = 0; i < N; i++) {
        double wo[3], wi[3], f[3], pdf; /* the directions as the set saw them, in float */
        get(bt->wo, i, wo);
        get(bt->wi, i, wi);
        bool valid = bt->flags[i] & LANES_BSDF_VALID, delta = bt->flags[i] & LANES_BSDF_DELTA;
        bool is_delta = b->kind == LANES_BSDF_MIRROR || b->kind == LANES_BSDF_GLASS;
        if (!CHECK(delta == is_delta, "%s %s: delta flag %d", isa, kind_names[b->kind], delta)) continue;
        if (!valid) {
            CHECK(!is_delta, "%s %s: a delta sample marked invalid", isa, kind_names[b->kind]);
            CHECK(bt->pdf[i] == 0.0f && bt->weight[i] == 0.0f && bt->weight[N + i] == 0.0f &&
                      bt->weight[2 * N + i] == 0.0f,
                  "%s %s: an invalid sample with pdf %g, weight %g %g %g", isa, kind_names[b->kind], (double)bt->pdf[i],
                  (double)bt->weight[i], (double)bt->weight[N + i], (double)bt->weight[2 * N + i]);
            continue;
        }
        double len = sqrt(wi[0] * wi[0] + wi[1] * wi[1] + wi[2] * wi[2]);
        if (!CHECK(fabs(len - 1.0) < 1e-5, "%s %s: |wi| = %.9f", isa, kind_names[b->kind], len)) continue;
        if (is_delta) {
            for (int k = 0; k < 3; k++)
                CHECK(bt->weight[(size_t)k * N + i] == b->albedo[k], "%s %s: delta weight %g, albedo %g", isa,
                      kind_names[b->kind], (double)bt->weight[(size_t)k * N + i], (double)b->albedo[k]);
            bool reflected = wi[2] * wo[2] > 0.0;
            if (reflected || b->kind == LANES_BSDF_MIRROR) {
                CHECK(near(wi[0], -wo[0]) && near(wi[1], -wo[1]) && near(wi[2], wo[2]),
                      "%s %s: reflection of (%g %g %g) is (%g %g %g)", isa, kind_names[b->kind], wo[0], wo[1], wo[2],
                      wi[0], wi[1], wi[2]);
            } else {
                /* Snell: eta_i sin_i = eta_t sin_t, in the plane of incidence */
                double eta_i = wo[2] > 0.0 ? 1.0 : b->ior, eta_t = wo[2] > 0.0 ? b->ior : 1.0;
                double sin_i = sqrt(wo[0] * wo[0] + wo[1] * wo[1]), sin_t = sqrt(wi[0] * wi[0] + wi[1] * wi[1]);
                CHECK(fabs(eta_i * sin_i - eta_t * sin_t) < 1e-5 && wi[0] * wo[0] + wi[1] * wo[1] <= 0.0,
                      "%s glass (ior %g): (%g %g %g) refracted to (%g %g %g)", isa, (double)b->ior, wo[0], wo[1],
                      wo[2], wi[0], wi[1], wi[2]);
                CHECK(ref_dielectric_fresnel(fabs(wo[2]), eta_i, eta_t) < 1.0,
                      "%s glass: refraction beyond the critical angle", isa);
            }
            continue;
        }
        if (!CHECK(wi[2] * wo[2] > 0.0 || (b->kind == LANES_BSDF_ROUGH_GLASS && wi[2] * wo[2] < 0.0),
                   "%s %s: sampled wi on the other side", isa, kind_names[b->kind]))
            continue;
        ref_bsdf_eval(b, wo, wi, f, &pdf);
        CHECK(near(bt->pdf[i], pdf) && pdf > 0.0, "%s %s (roughness %g): sample pdf %g, reference %g", isa,
              kind_names[b->kind], (double)b->roughness, (double)bt->pdf[i], pdf);
        for (int k = 0; k < 3; k++) {
            double want = f[k] * fabs(wi[2]) / pdf, got = bt->weight[(size_t)k * N + i];
            CHECK(fabs(got - want) <= 4 * REL_TOL * want + ABS_TOL, "%s %s: weight %g, reference f cos / pdf %g", isa,
                  kind_names[b->kind], got, want);
        }
    }
}

/* The directional albedo: the integral of f cos over the sphere, by the
 * midpoint rule in (theta, phi), fine in theta (a lobe of roughness 0.3
 * spans about 0.2 radians; a grid even in cos theta resolved it poorly at
 * normal incidence, off by 0.3%), channel 0. */
static double albedo_quadrature(const lanes_bsdf *b, const double wo[3])
{
    enum { T = 1500, P = 400 };
    double sum = 0.0;
    for (int i = 0; i < T; i++) {
        double th = PI * (i + 0.5) / T, z = cos(th), s = sin(th), row = 0.0;
        for (int j = 0; j < P; j++) {
            double phi = 2.0 * PI * (j + 0.5) / P;
            double wi[3] = {s * cos(phi), s * sin(phi), z}, f[3], pdf;
            ref_bsdf_eval(b, wo, wi, f, &pdf);
            row += f[0] * fabs(z);
        }
        sum += row * s;
    }
    return sum * (PI / T) * (2.0 * PI / P);
}

static void test_sampling(const char *isa, sample_fn sample, batch *bt, harness_rng *r)
{
    /* every sample, random parameters and directions */
    for (int kind = 0; kind <= LANES_BSDF_ROUGH_GLASS; kind++)
        for (int round = 0; round < 8; round++) {
            lanes_bsdf b = random_bsdf(r, (lanes_bsdf_kind)kind);
            double wo[3];
            random_direction(r, wo);
            sample_batch(sample, bt, &b, wo, r);
            check_samples(isa, &b, bt);
        }

    /* unbiased, and at most 1, for white surfaces at three angles */
    static const lanes_bsdf_kind kinds[] = {LANES_BSDF_LAMBERT, LANES_BSDF_CONDUCTOR, LANES_BSDF_PLASTIC};
    static const float roughness[] = {0.3f, 0.7f};
    static const double angles[] = {0.0, 45.0, 80.0};
    for (size_t k = 0; k < 3; k++)
        for (size_t g = 0; g < 2; g++)
            for (size_t a = 0; a < 3; a++) {
                lanes_bsdf b = {.kind = kinds[k], .albedo = {1, 1, 1}, .f0 = {1, 1, 1}, .roughness = roughness[g]};
                double t = angles[a] * PI / 180.0, wo[3] = {sin(t), 0.0, cos(t)};
                double sum = 0.0, sum2 = 0.0;
                for (int rep = 0; rep < 8; rep++) {
                    sample_batch(sample, bt, &b, wo, r);
                    for (size_t i = 0; i < N; i++) sum += bt->weight[i], sum2 += (double)bt->weight[i] * bt->weight[i];
                }
                double n = 8.0 * N, mean = sum / n, sd = sqrt(fmax(0.0, sum2 / n - mean * mean) / n);
                /* the same for every set: integrated once */
                static double cached[3][2][3];
                if (cached[k][g][a] == 0.0) cached[k][g][a] = albedo_quadrature(&b, wo);
                double want = cached[k][g][a];
                CHECK(want <= 1.0 + 1e-3, "%s %s (roughness %g) at %g degrees: albedo %.5f above 1", isa,
                      kind_names[b.kind], (double)b.roughness, angles[a], want);
                CHECK(fabs(mean - want) <= 5.0 * sd + 2e-3,
                      "%s %s (roughness %g) at %g degrees: mean weight %.5f +- %.5f, albedo %.5f", isa,
                      kind_names[b.kind], (double)b.roughness, angles[a], mean, sd, want);
            }

    /* glass reflects with the Fresnel probability, from outside and inside */
    static const double glass_angles[] = {10.0, 60.0, 85.0, 170.0, 140.0};
    for (size_t a = 0; a < sizeof glass_angles / sizeof glass_angles[0]; a++) {
        lanes_bsdf b = {.kind = LANES_BSDF_GLASS, .albedo = {1, 1, 1}, .ior = 1.5f};
        double t = glass_angles[a] * PI / 180.0, wo[3] = {sin(t), 0.0, cos(t)};
        sample_batch(sample, bt, &b, wo, r);
        long reflected = 0;
        for (size_t i = 0; i < N; i++) reflected += bt->wi[2 * N + i] * wo[2] > 0.0;
        double outside = wo[2] > 0.0;
        double p = ref_dielectric_fresnel(fabs(wo[2]), outside ? 1.0 : 1.5, outside ? 1.5 : 1.0);
        double sd = sqrt(p * (1.0 - p) / N);
        CHECK(fabs((double)reflected / N - p) <= 5.0 * sd + 1e-9, "%s glass at %g degrees: reflected %.4f, Fresnel %.4f",
              isa, glass_angles[a], (double)reflected / N, p);
    }

    /* rough glass, white: unbiased, and at most 1 (without the radiance
     * scaling the mean weight is the part of the light the surface keeps,
     * reflected or transmitted), from outside and from inside (angles past
     * 90), denser and less dense inside */
    static const struct {
        float roughness, ior;
        double angle;
    } rg[] = {{0.3f, 1.5f, 0.0},    {0.3f, 1.5f, 45.0},  {0.3f, 1.5f, 80.0},  {0.3f, 1.5f, 180.0}, {0.3f, 1.5f, 135.0},
              {0.3f, 1.5f, 100.0},  {0.7f, 1.5f, 0.0},   {0.7f, 1.5f, 45.0},  {0.7f, 1.5f, 80.0},  {0.7f, 1.5f, 180.0},
              {0.7f, 1.5f, 135.0},  {0.7f, 1.5f, 100.0}, {0.5f, 0.75f, 30.0}, {0.5f, 0.75f, 150.0}};
    enum { RG = sizeof rg / sizeof rg[0] };
    for (size_t c = 0; c < RG; c++) {
        lanes_bsdf b = {.kind = LANES_BSDF_ROUGH_GLASS, .albedo = {1, 1, 1}, .roughness = rg[c].roughness,
                        .ior = rg[c].ior};
        double t = rg[c].angle * PI / 180.0, wo[3] = {sin(t), 0.0, cos(t)};
        double sum = 0.0, sum2 = 0.0;
        for (int rep = 0; rep < 8; rep++) {
            sample_batch(sample, bt, &b, wo, r);
            for (size_t i = 0; i < N; i++) sum += bt->weight[i], sum2 += (double)bt->weight[i] * bt->weight[i];
        }
        double n = 8.0 * N, mean = sum / n, sd = sqrt(fmax(0.0, sum2 / n - mean * mean) / n);
        static double cached[RG];
        if (cached[c] == 0.0) cached[c] = albedo_quadrature(&b, wo);
        double want = cached[c];
        CHECK(want <= 1.0 + 1e-3, "%s rough_glass (roughness %g, ior %g) at %g degrees: albedo %.5f above 1", isa,
              (double)b.roughness, (double)b.ior, rg[c].angle, want);
        CHECK(mean <= 1.0 + 5.0 * sd + 1e-3,
              "%s rough_glass (roughness %g, ior %g) at %g degrees: mean weight %.5f +- %.5f above 1", isa,
              (double)b.roughness, (double)b.ior, rg[c].angle, mean, sd);
        CHECK(fabs(mean - want) <= 5.0 * sd + 2e-3,
              "%s rough_glass (roughness %g, ior %g) at %g degrees: mean weight %.5f +- %.5f, albedo %.5f", isa,
              (double)b.roughness, (double)b.ior, rg[c].angle, mean, sd, want);
        printf("  %s rough_glass (roughness %.1f, ior %.2f) at %.0f degrees: mean weight %.5f +- %.5f, albedo %.5f\n",
               isa, (double)b.roughness, (double)b.ior, rg[c].angle, mean, sd, want);
    }
}

/* ---- chi-square of the sampled directions ------------------------------ */

/* Q(a, x), the regularized upper incomplete gamma function: the p-value of
 * a chi-square statistic x2 with d degrees of freedom is Q(d/2, x2/2). */
static double gamma_q(double a, double x)
{
    if (x <= 0.0) return 1.0;
    double front = exp(-x + a * log(x) - lgamma(a));
    if (x < a + 1.0) {
        double term = 1.0 / a, sum = term;
        for (int n = 1; n < 10000 && term > sum * 1e-16; n++) {
            term *= x / (a + n);
            sum += term;
        }
        return 1.0 - front * sum;
    }
    /* continued fraction, by Lentz's method */
    double b = x + 1.0 - a, c = 1e300, d = 1.0 / b, h = d;
    for (int i = 1; i < 10000; i++) {
        double an = -i * (i - a);
        b += 2.0;
        d = an * d + b;
        if (fabs(d) < 1e-300) d = 1e-300;
        c = b + an / c;
        if (fabs(c) < 1e-300) c = 1e-300;
        d = 1.0 / d;
        double del = d * c;
        h *= del;
        if (fabs(del - 1.0) < 1e-16) break;
    }
    return front * h;
}

enum { ZB = 16, PB = 32, SUB = 4, ROUNDS = 16 };

static void chi_square(const char *isa, sample_fn sample, batch *bt, harness_rng *r, lanes_bsdf b, double theta)
{
    double t = theta * PI / 180.0, wo[3] = {sin(t), 0.0, cos(t)};
    static double expected[2 * ZB * PB + 1];
    static long observed[2 * ZB * PB + 1];
    memset(observed, 0, sizeof observed);
    /* bins over the upper hemisphere in (z, phi), for rough glass over the
     * sphere (z from -1, twice the rows), and one for no direction. Rough
     * glass's transmitted lobe is narrower than its microfacets' (a third
     * at normal incidence into ior 1.5): 16 x 16 points integrate a bin. */
    const bool sphere = b.kind == LANES_BSDF_ROUGH_GLASS;
    const int zb = sphere ? 2 * ZB : ZB, sub = sphere ? 4 * SUB : SUB, nb = zb * PB;
    const double z0 = sphere ? -1.0 : 0.0, dz = (1.0 - z0) / zb;
    double total = 0.0;
    for (int i = 0; i < zb; i++)
        for (int j = 0; j < PB; j++) {
            double sum = 0.0;
            for (int si = 0; si < sub; si++)
                for (int sj = 0; sj < sub; sj++) {
                    double z = z0 + (i + (si + 0.5) / sub) * dz, phi = 2.0 * PI * (j + (sj + 0.5) / sub) / PB;
                    double s = sqrt(1.0 - z * z), wi[3] = {s * cos(phi), s * sin(phi), z}, f[3], pdf;
                    ref_bsdf_eval(&b, wo, wi, f, &pdf);
                    sum += pdf;
                }
            expected[i * PB + j] = sum / (sub * sub) * dz * (2.0 * PI / PB);
            total += expected[i * PB + j];
        }
    expected[nb] = fmax(0.0, 1.0 - total);
    for (int round = 0; round < ROUNDS; round++) {
        sample_batch(sample, bt, &b, wo, r);
        for (size_t i = 0; i < N; i++) {
            if (!(bt->flags[i] & LANES_BSDF_VALID)) {
                observed[nb]++;
                continue;
            }
            double z = bt->wi[2 * N + i], phi = atan2(bt->wi[N + i], bt->wi[i]);
            if (phi < 0.0) phi += 2.0 * PI;
            int zi = (int)floor((z - z0) / dz), pj = (int)(phi / (2.0 * PI) * PB);
            zi = zi < 0 ? 0 : zi >= zb ? zb - 1 : zi;
            pj = pj < 0 ? 0 : pj >= PB ? PB - 1 : pj;
            observed[zi * PB + pj]++;
        }
    }
    /* bins expecting fewer than 5 samples pooled into one */
    const double n = (double)ROUNDS * N;
    double chi2 = 0.0, pool_e = 0.0;
    long pool_o = 0;
    int bins = 0;
    for (int k = 0; k <= nb; k++) {
        double e = expected[k] * n;
        if (e < 5.0) {
            pool_e += e, pool_o += observed[k];
            continue;
        }
        chi2 += (observed[k] - e) * (observed[k] - e) / e;
        bins++;
    }
    if (pool_e > 0.0) {
        chi2 += (pool_o - pool_e) * (pool_o - pool_e) / fmax(pool_e, 1.0);
        bins++;
    }
    double p = gamma_q((bins - 1) / 2.0, chi2 / 2.0);
    char ior[32] = "";
    if (sphere) snprintf(ior, sizeof ior, ", ior %.2f", (double)b.ior);
    printf("  %s %s (roughness %.1f%s) at %.0f degrees: chi-square %.1f over %d bins, p = %.3f\n", isa,
           kind_names[b.kind], (double)b.roughness, ior, theta, chi2, bins, p);
    /* about twenty such tests per set: 1e-3 each keeps a correct sampler's
     * chance of failing one low, and a wrong pdf gives p ~ 0 */
    CHECK(p > 1e-3, "%s %s (roughness %g%s) at %g degrees: the sampled directions do not follow the pdf (p = %.2g)",
          isa, kind_names[b.kind], (double)b.roughness, ior, theta, p);
}

static void test_chi_square(const char *isa, sample_fn sample, batch *bt, harness_rng *r)
{
    static const double thetas[] = {30.0, 75.0};
    for (size_t a = 0; a < 2; a++) {
        chi_square(isa, sample, bt, r, (lanes_bsdf){.kind = LANES_BSDF_LAMBERT, .albedo = {0.8f, 0.5f, 0.2f}},
                   thetas[a]);
        chi_square(isa, sample, bt, r,
                   (lanes_bsdf){.kind = LANES_BSDF_CONDUCTOR, .f0 = {0.9f, 0.6f, 0.3f}, .roughness = 0.4f}, thetas[a]);
        chi_square(isa, sample, bt, r,
                   (lanes_bsdf){.kind = LANES_BSDF_CONDUCTOR, .f0 = {0.9f, 0.6f, 0.3f}, .roughness = 0.8f}, thetas[a]);
        chi_square(isa, sample, bt, r,
                   (lanes_bsdf){.kind = LANES_BSDF_PLASTIC, .albedo = {0.2f, 0.5f, 0.8f}, .roughness = 0.5f}, thetas[a]);
        /* rough glass from outside and inside, and less dense inside (from
         * outside at 75 degrees beyond the critical angle of the mean surface) */
        const lanes_bsdf glass = {.kind = LANES_BSDF_ROUGH_GLASS, .albedo = {0.9f, 0.8f, 0.7f}, .roughness = 0.5f,
                                  .ior = 1.5f};
        chi_square(isa, sample, bt, r, glass, thetas[a]);
        chi_square(isa, sample, bt, r, glass, 180.0 - thetas[a]);
        chi_square(isa, sample, bt, r,
                   (lanes_bsdf){.kind = LANES_BSDF_ROUGH_GLASS, .albedo = {1, 1, 1}, .roughness = 0.8f, .ior = 0.75f},
                   thetas[a]);
    }
}

/* Rough glass where nothing scatters or no microfacet explains the pair:
 * f = pdf = 0, never NaN, and likewise the transmission of an
 * index-matched surface (|ior - 1| < LANES_BSDF_MIN_IOR_GAP: a delta,
 * straight through, which the lobe does not hold); sampled from a
 * direction in the plane, or at ior 1 (where F = 0 too, so nothing
 * reflects), no valid direction and every weight and pdf 0. */
static void test_degenerate(const char *isa, eval_fn eval, sample_fn sample, batch *bt)
{
    static const struct {
        double wo[3], wi[3];
        bool zero; /* at ior 1.5 */
    } cases[] = {
        {{1, 0, 0}, {0, 0, 1}, true},            /* wo in the plane */
        {{0, 0, 1}, {1, 0, 0}, true},            /* wi in the plane */
        {{0, 0, -1}, {-1, 0, 0}, true},          /* from inside */
        {{1, 0, 0}, {-1, 0, 0}, true},           /* both, opposed: no half vector */
        {{0, 0, -0.0}, {0, 0, 1}, true},         /* wo.z = -0 */
        {{0.6, 0, 0.8}, {0.6, 0, -0.8}, true},   /* wo behind the only microfacet */
        {{0.6, 0, 0.8}, {-0.6, 0, -0.8}, false}, /* straight through (a tilted facet); at ior 1 no h */
        {{0, 0, 1}, {0, 0, -1}, false},          /* likewise */
        {{0, 0, 1}, {0, 0, 1}, false},           /* D's peak */
        {{0, 0, -1}, {0, 0, -1}, false},         /* D's peak, from inside */
    };
    enum { C = sizeof cases / sizeof cases[0] };
    static const float iors[] = {1.5f, 1.0f, 1.00005f}, roughness[] = {0.0f, 0.5f};
    for (size_t q = 0; q < 3; q++)
        for (size_t g = 0; g < 2; g++) {
            lanes_bsdf b = {.kind = LANES_BSDF_ROUGH_GLASS, .albedo = {1, 1, 1}, .roughness = roughness[g],
                            .ior = iors[q]};
            for (size_t i = 0; i < N; i++) put(bt->wo, i, cases[i % C].wo), put(bt->wi, i, cases[i % C].wi);
            eval(&b, N, NULL, bt->wo, bt->wi, bt->f, bt->pdf);
            bool matched = fabs(b.ior - 1.0) < LANES_BSDF_MIN_IOR_GAP;
            for (size_t j = 0; j < N; j++) {
                size_t i = j % C;
                bool zero = cases[i].zero || b.ior == 1.0f || (matched && cases[i].wo[2] * cases[i].wi[2] < 0.0);
                float f = bt->f[j], pdf = bt->pdf[j];
                bool finite = isfinite(pdf) && isfinite(f) && isfinite(bt->f[N + j]) && isfinite(bt->f[2 * N + j]);
                CHECK(finite && (zero ? pdf == 0.0f && f == 0.0f : pdf > 0.0f && f > 0.0f),
                      "%s rough_glass (roughness %g, ior %g): f(wo (%g %g %g), wi (%g %g %g)) = %g, pdf %g", isa,
                      (double)b.roughness, (double)b.ior, cases[i].wo[0], cases[i].wo[1], cases[i].wo[2],
                      cases[i].wi[0], cases[i].wi[1], cases[i].wi[2], (double)f, (double)pdf);
            }
            static const double wos[][3] = {{1, 0, 0}, {0, -1, 0}, {0.6, 0, 0.8}, {0, 0.8, -0.6}};
            for (size_t w = 0; w < 4; w++) {
                if (w >= 2 && b.ior != 1.0f) continue;
                harness_rng r = harness_rng_seed(0xde9 + w);
                sample_batch(sample, bt, &b, wos[w], &r);
                size_t bad = 0;
                for (size_t i = 0; i < N; i++)
                    bad += (bt->flags[i] & LANES_BSDF_VALID) || bt->pdf[i] != 0.0f || bt->weight[i] != 0.0f ||
                           bt->weight[N + i] != 0.0f || bt->weight[2 * N + i] != 0.0f;
                CHECK(bad == 0, "%s rough_glass (roughness %g, ior %g) from (%g %g %g): %zu samples valid or not 0",
                      isa, (double)b.roughness, (double)b.ior, wos[w][0], wos[w][1], wos[w][2], bad);
            }
        }
}

/* Calls on n items that fill no whole vector at the end: each item as in
 * a full call, nothing written past n; and with an albedo per item (a
 * texture's), each item as the material with that albedo. */
static void test_tail(const char *isa, const lanes_kernels *k, harness_rng *r, lanes_bsdf_kind kind)
{
    enum { M = 37, GUARD = 16 };
    static float wo[3 * M], wi[3 * M], u[3 * M], f[3 * M + GUARD], pdf[M + GUARD], w2[3 * M + GUARD];
    static uint8_t flags[M + GUARD];
    lanes_bsdf b = random_bsdf(r, kind);
    for (size_t i = 0; i < M; i++) {
        double d[3];
        random_direction(r, d);
        for (int c = 0; c < 3; c++) wo[c * M + i] = (float)d[c], u[c * M + i] = (float)harness_uniform(r);
        random_direction(r, d);
        for (int c = 0; c < 3; c++) wi[c * M + i] = (float)d[c];
    }
    for (size_t n = 1; n <= M; n += 6) {
        for (size_t i = 0; i < 3 * M + GUARD; i++) f[i] = w2[i] = -7.0f;
        for (size_t i = 0; i < M + GUARD; i++) pdf[i] = -7.0f, flags[i] = 0xee;
        /* the first n items, their components n apart */
        float o[3 * M], v[3 * M], uu[3 * M];
        for (int c = 0; c < 3; c++)
            for (size_t i = 0; i < n; i++) o[c * n + i] = wo[c * M + i], v[c * n + i] = wi[c * M + i], uu[c * n + i] = u[c * M + i];
        k->bsdf_eval(&b, n, NULL, o, v, f, pdf);
        for (size_t i = 0; i < n; i++) {
            double dwo[3] = {o[i], o[n + i], o[2 * n + i]}, dwi[3] = {v[i], v[n + i], v[2 * n + i]}, ff[3], pp;
            ref_bsdf_eval(&b, dwo, dwi, ff, &pp);
            CHECK(near(f[i], ff[0]) && near(f[2 * n + i], ff[2]) && near(pdf[i], pp), "%s: bsdf_eval of %zu items, item %zu", isa, n, i);
        }
        CHECK(f[3 * n] == -7.0f && pdf[n] == -7.0f, "%s: bsdf_eval of %zu items wrote past them", isa, n);
        float albedo[3 * M];
        for (size_t i = 0; i < 3 * n; i++) albedo[i] = (float)harness_uniform(r);
        k->bsdf_eval(&b, n, albedo, o, v, f, pdf);
        for (size_t i = 0; i < n; i++) {
            double dwo[3] = {o[i], o[n + i], o[2 * n + i]}, dwi[3] = {v[i], v[n + i], v[2 * n + i]}, ff[3], pp;
            lanes_bsdf own = b;
            for (int c = 0; c < 3; c++) own.albedo[c] = albedo[c * n + i];
            ref_bsdf_eval(&own, dwo, dwi, ff, &pp);
            bool ok = near(pdf[i], pp);
            for (int c = 0; c < 3; c++) ok = ok && near(f[c * n + i], ff[c]);
            CHECK(ok, "%s: bsdf_eval of %zu items with their own albedo, item %zu", isa, n, i);
        }
        k->bsdf_sample(&b, n, NULL, o, uu, w2, f, pdf, flags);
        CHECK(w2[3 * n] == -7.0f && f[3 * n] == -7.0f && pdf[n] == -7.0f && flags[n] == 0xee,
              "%s: bsdf_sample of %zu items wrote past them", isa, n);
    }
}

int main(int argc, char **argv)
{
    const char *isa_list = NULL;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--isa") == 0 && i + 1 < argc) {
            isa_list = argv[++i];
        } else {
            fprintf(stderr, "usage: %s [--isa a,b,...]\n  sets: %s\n", argv[0], lanes_isa_all_names());
            return 2;
        }
    }
    batch *bt = malloc(sizeof *bt);
    if (!bt) {
        fprintf(stderr, "test_bsdf: out of memory\n");
        return 2;
    }
    printf("test_bsdf: CPU %s\n", lanes_cpu()->brand);
    for (int i = 0; i < LANES_ISA_COUNT; i++) {
        lanes_isa isa = (lanes_isa)i;
        const char *name = lanes_isa_name(isa);
        if (!harness_in_list(isa_list, name) || !lanes_isa_compiled(isa)) continue;
        if (!lanes_isa_cpu_can_run(isa)) {
            printf("SKIP %s: this CPU cannot run it\n", name);
            harness_skip();
            continue;
        }
        /* the same seed for every set: the sets see the same directions */
        harness_rng r = harness_rng_seed(0xb5df);
        const lanes_kernels *k = lanes_kernels_for(isa);
        test_eval(name, k->bsdf_eval, bt, &r);
        test_sampling(name, k->bsdf_sample, bt, &r);
        test_chi_square(name, k->bsdf_sample, bt, &r);
        test_tail(name, k, &r, LANES_BSDF_PLASTIC);
        test_tail(name, k, &r, LANES_BSDF_ROUGH_GLASS);
        test_degenerate(name, k->bsdf_eval, k->bsdf_sample, bt);
    }
    free(bt);
    return harness_summary("test_bsdf");
}
