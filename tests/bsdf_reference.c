/* Double-precision BSDFs for tests/test_bsdf.c (see bsdf_reference.h). */
#include "bsdf_reference.h"

#include <math.h>
#include <stdbool.h>

#define REF_PI 3.14159265358979323846

static double dot(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static double alpha_of(const lanes_bsdf *b)
{
    double a = (double)b->roughness * (double)b->roughness;
    return a > (double)LANES_BSDF_MIN_ALPHA ? a : (double)LANES_BSDF_MIN_ALPHA;
}

/* D(h) = 1 / (pi a^2 cos^4 (1 + tan^2 / a^2)^2) */
static double ggx_d(double a, double cos_h)
{
    double c2 = cos_h * cos_h, tan2 = (1.0 - c2) / c2;
    double k = 1.0 + tan2 / (a * a);
    return 1.0 / (REF_PI * a * a * c2 * c2 * k * k);
}

/* G1 = 1 / (1 + Lambda), Lambda = (sqrt(1 + a^2 tan^2) - 1) / 2 */
static double ggx_g1(double a, double cos_t)
{
    double tan2 = (1.0 - cos_t * cos_t) / (cos_t * cos_t);
    return 2.0 / (1.0 + sqrt(1.0 + a * a * tan2));
}

static double schlick(double f0, double c) { return f0 + (1.0 - f0) * pow(1.0 - c, 5.0); }

/* The GGX reflection lobe: common factor D G / (4 cos_o cos_i), the
 * half-vector angle's cosine with wo, and the lobe's sampling pdf. */
static double ggx_lobe(double a, const double wo[3], const double wi[3], double *c, double *pdf)
{
    double h[3] = {wo[0] + wi[0], wo[1] + wi[1], wo[2] + wi[2]};
    double len = sqrt(dot(h, h));
    for (int k = 0; k < 3; k++) h[k] /= len;
    /* the angle between either direction and h, symmetrically: (wo . h +
     * wi . h) / 2 = |wo + wi| / 2. (wo . h alone, for directions a float's
     * rounding away from unit length, depends on which one is wo where
     * they nearly oppose.) */
    *c = 0.5 * len;
    double d = ggx_d(a, h[2]);
    *pdf = d * h[2] / (4.0 * *c);
    return d * ggx_g1(a, wo[2]) * ggx_g1(a, wi[2]) / (4.0 * wo[2] * wi[2]);
}

/* Rough glass as Walter, Marschner, Li and Torrance (2007) write it, with
 * their i the direction light comes from (wi here, index eta_i on its side)
 * and o the one it leaves by (wo, eta_o); +z outside (index 1), -z inside
 * (ior). The half vectors of their eqs. 13 and 16, h_r = sign(i . n)(i + o)
 * and h_t = -(eta_i i + eta_o o), normalized and, for h_t, turned to +z;
 * the chi+ of G1 (each direction on its own side of the microfacet); f_r by
 * eq. 20, f_t by eq. 21 and then times (eta_i / eta_o)^2, dropping the
 * radiance scaling as the library's glass does. The pdf of a sampler that
 * draws m from D(m) |m . n| (eq. 38) and, from wo's side, reflects with
 * probability F: that times D |h . n| and the Jacobian of eq. 14 or 17,
 * there with the generated direction (wi) in the role of o. */
static void ref_rough_glass(const lanes_bsdf *b, const double wo[3], const double wi[3], double f[3], double *pdf)
{
    if (wo[2] == 0.0 || wi[2] == 0.0) return;
    double ior = b->ior, a = alpha_of(b);
    bool reflection = (wo[2] > 0.0) == (wi[2] > 0.0);
    if (!reflection && fabs(ior - 1.0) < (double)LANES_BSDF_MIN_IOR_GAP) return; /* index-matched */
    double eta_o = wo[2] > 0.0 ? 1.0 : ior, eta_i = wi[2] > 0.0 ? 1.0 : ior;
    double h[3];
    if (reflection) {
        double s = wi[2] > 0.0 ? 1.0 : -1.0;
        for (int k = 0; k < 3; k++) h[k] = s * (wi[k] + wo[k]);
    } else {
        for (int k = 0; k < 3; k++) h[k] = -(eta_i * wi[k] + eta_o * wo[k]);
    }
    double len = sqrt(dot(h, h));
    if (!(len > 0.0)) return;
    double s = h[2] < 0.0 ? -1.0 : 1.0;
    for (int k = 0; k < 3; k++) h[k] *= s / len;
    double i_h = dot(wi, h), o_h = dot(wo, h);
    if (!(i_h * wi[2] > 0.0 && o_h * wo[2] > 0.0)) return;
    double d = ggx_d(a, h[2]), g = ggx_g1(a, fabs(wi[2])) * ggx_g1(a, fabs(wo[2]));
    double value, p;
    if (reflection) {
        /* both angles with h as |wo + wi| / 2, as in ggx_lobe */
        double c = 0.5 * len;
        double fr = ref_dielectric_fresnel(c, eta_o, wo[2] > 0.0 ? ior : 1.0);
        value = fr * g * d / (4.0 * fabs(wi[2]) * fabs(wo[2]));
        p = fr * d * h[2] / (4.0 * c);
    } else {
        /* F(i, h_t) by Fresnel's equations with both angles, the cosines
         * with h_t: a float's direction is a little off unit length, so
         * a cosine from the other one by Snell's law (ref_dielectric_fresnel)
         * would lose digits where it is small: 1e-3 relative at cos 0.01 */
        double ci = fabs(i_h), co = fabs(o_h);
        double rs = (eta_i * ci - eta_o * co) / (eta_i * ci + eta_o * co);
        double rp = (eta_o * ci - eta_i * co) / (eta_o * ci + eta_i * co);
        double fr = 0.5 * (rs * rs + rp * rp);
        double den = eta_i * i_h + eta_o * o_h;
        double ft = fabs(i_h) * fabs(o_h) / (fabs(wi[2]) * fabs(wo[2])) * eta_o * eta_o * (1.0 - fr) * g * d /
                    (den * den);
        value = ft * (eta_i / eta_o) * (eta_i / eta_o);
        p = (1.0 - fr) * d * h[2] * eta_i * eta_i * fabs(i_h) / (den * den);
    }
    for (int k = 0; k < 3; k++) f[k] = b->albedo[k] * value;
    *pdf = p;
}

void ref_bsdf_eval(const lanes_bsdf *b, const double wo_in[3], const double wi_in[3], double f[3], double *pdf)
{
    f[0] = f[1] = f[2] = 0.0;
    *pdf = 0.0;
    if (b->kind == LANES_BSDF_MIRROR || b->kind == LANES_BSDF_GLASS) return;
    if (b->kind == LANES_BSDF_ROUGH_GLASS) {
        ref_rough_glass(b, wo_in, wi_in, f, pdf);
        return;
    }
    double s = wo_in[2] < 0.0 ? -1.0 : 1.0;
    const double wo[3] = {wo_in[0], wo_in[1], s * wo_in[2]}, wi[3] = {wi_in[0], wi_in[1], s * wi_in[2]};
    if (!(wo[2] > 0.0 && wi[2] > 0.0)) return;
    double c, lobe_pdf;
    switch (b->kind) {
    case LANES_BSDF_LAMBERT:
        for (int k = 0; k < 3; k++) f[k] = b->albedo[k] / REF_PI;
        *pdf = wi[2] / REF_PI;
        break;
    case LANES_BSDF_CONDUCTOR: {
        double common = ggx_lobe(alpha_of(b), wo, wi, &c, &lobe_pdf);
        for (int k = 0; k < 3; k++) f[k] = common * schlick(b->f0[k], c);
        *pdf = lobe_pdf;
        break;
    }
    case LANES_BSDF_PLASTIC: {
        double f0 = LANES_BSDF_COAT_F0;
        double spec = ggx_lobe(alpha_of(b), wo, wi, &c, &lobe_pdf) * schlick(f0, c);
        double through = (1.0 - schlick(f0, wo[2])) * (1.0 - schlick(f0, wi[2])) / REF_PI;
        for (int k = 0; k < 3; k++) f[k] = spec + through * b->albedo[k];
        double pick = LANES_BSDF_COAT_PICK;
        *pdf = pick * lobe_pdf + (1.0 - pick) * wi[2] / REF_PI;
        break;
    }
    default:
        break;
    }
}

double ref_dielectric_fresnel(double ci, double eta_i, double eta_t)
{
    double sin_t = eta_i / eta_t * sqrt(fmax(0.0, 1.0 - ci * ci));
    if (sin_t >= 1.0) return 1.0;
    double ct = sqrt(1.0 - sin_t * sin_t);
    double rs = (eta_i * ci - eta_t * ct) / (eta_i * ci + eta_t * ct);
    double rp = (eta_t * ci - eta_i * ct) / (eta_t * ci + eta_i * ct);
    return 0.5 * (rs * rs + rp * rp);
}
