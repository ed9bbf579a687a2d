/* The BSDFs of trace/bsdf.h on LANES_W directions at once, written once
 * and compiled per set: eval (the BSDF's value f), pdf (of bsdf_sample's
 * directions, per unit solid angle) and sample. The parameters are uniform
 * (one material per call, as a shading batch is); the directions are per
 * lane, in the shading frame (normal +z). Lanes outside `live` compute
 * garbage that the caller ignores.
 *
 * Opaque kinds are two-sided: with wo below the surface both directions
 * are mirrored first. They reflect only, so f = 0 when wi is on the other
 * side. Mirror and glass are delta distributions: eval and pdf are 0, and
 * bsdf_sample marks its lanes `delta`, with the weight that replaces
 * f cos / pdf.
 *
 * GGX (Trowbridge-Reitz) with the separable Smith shadowing-masking term;
 * its samples are drawn from D(h) cos(theta_h) and reflected (Walter et al.
 * 2007), which gives the pdf in closed form. Rough glass, the same
 * microfacets on a dielectric, reflects or refracts through them (see
 * rough_glass_eval): both sides, not a delta lobe. tests/test_bsdf.c checks
 * all of it against double-precision references.
 *
 * Included by per-ISA files; everything is static inline. */
#ifndef LANES_TRACE_KERNELS_BSDF_CORE_H
#define LANES_TRACE_KERNELS_BSDF_CORE_H

#include "simd/simd.h"
#include "simd/vmath.h"
#include "trace/bsdf.h"

typedef struct {
    vfloat x, y, z;
} bsdf_v3;

typedef struct {
    bsdf_v3 wi;
    bsdf_v3 weight; /* f cos(theta_i) / pdf, or the delta lobe's weight */
    vfloat pdf;     /* 0 on delta lanes */
    vmask valid;    /* a direction was made (not below the surface, not absorbed) */
    vmask delta;
} bsdf_sample_result;

#define BSDF_PI 3.14159265358979f

static inline vfloat bsdf_alpha2(const lanes_bsdf *b)
{
    float a = b->roughness * b->roughness;
    a = a > LANES_BSDF_MIN_ALPHA ? a : LANES_BSDF_MIN_ALPHA;
    return vf_set1(a * a);
}

/* D(h) = a2 / (pi (sin^2 + a2 cos^2)^2), the sine from h's x and y: the
 * usual 1 + cos^2 (a2 - 1) cancels near the peak, where a sharp lobe's
 * pdf needs sin^2 to a few ulps (2e-4 relative error at roughness 0.05). */
static inline vfloat ggx_d(vfloat a2, bsdf_v3 h)
{
    vfloat t = vf_fmadd(vf_mul(h.z, h.z), a2, vf_fmadd(h.x, h.x, vf_mul(h.y, h.y)));
    return vf_div(a2, vf_mul(vf_set1(BSDF_PI), vf_mul(t, t)));
}

/* Smith's G1 for a direction at cos(theta) = c > 0. */
static inline vfloat ggx_g1(vfloat a2, vfloat c)
{
    vfloat c2 = vf_mul(c, c);
    vfloat root = vf_sqrt(vf_fmadd(vf_sub(vf_set1(1.0f), a2), c2, a2));
    return vf_div(vf_add(c, c), vf_add(c, root));
}

/* Schlick's Fresnel: f0 + (1 - f0) (1 - c)^5. */
static inline vfloat schlick(vfloat f0, vfloat c)
{
    vfloat m = vf_max(vf_sub(vf_set1(1.0f), c), vf_zero());
    vfloat m2 = vf_mul(m, m);
    return vf_fmadd(vf_sub(vf_set1(1.0f), f0), vf_mul(vf_mul(m2, m2), m), f0);
}

/* Fresnel reflectance of a smooth dielectric for light arriving at
 * cos(theta) = ci from the side of index eta_i onto eta_t; 1 beyond the
 * critical angle. *ct receives cos(theta_t). */
static inline vfloat dielectric_fresnel(vfloat ci, vfloat eta_i, vfloat eta_t, vfloat *ct)
{
    vfloat eta = vf_div(eta_i, eta_t), one = vf_set1(1.0f);
    vfloat sin2t = vf_mul(vf_mul(eta, eta), vf_max(vf_fnmadd(ci, ci, one), vf_zero()));
    vmask tir = vf_ge(sin2t, one);
    vfloat c = vf_sqrt(vf_max(vf_sub(one, sin2t), vf_zero()));
    vfloat a = vf_mul(eta_i, ci), bb = vf_mul(eta_t, c), p = vf_mul(eta_t, ci), q = vf_mul(eta_i, c);
    vfloat rs = vf_div(vf_sub(a, bb), vf_add(a, bb)), rp = vf_div(vf_sub(p, q), vf_add(p, q));
    vfloat fr = vf_mul(vf_set1(0.5f), vf_fmadd(rs, rs, vf_mul(rp, rp)));
    *ct = c;
    return vf_select(tir, one, fr);
}

/* The Fresnel transmittance 1 - F of a smooth dielectric for a refraction
 * pair known on both sides: cos ca on the side of index ea, cos cb on the
 * side of eb (ea sin_a = eb sin_b). Each polarization's 1 - r^2, for
 * r = (x - y) / (x + y), as 4 x y / (x + y)^2: 1 - dielectric_fresnel
 * cancels where F nears 1 (grazing on the thin side, near the critical
 * angle on the dense one), where its cos(theta_t) by Snell's law loses
 * digits as well (1e-3 relative at cos 0.01); this form is symmetric in the
 * two sides, as the transmittance is. */
static inline vfloat dielectric_transmittance(vfloat ca, vfloat cb, vfloat ea, vfloat eb)
{
    vfloat s = vf_fmadd(ea, ca, vf_mul(eb, cb)), p = vf_fmadd(eb, ca, vf_mul(ea, cb));
    vfloat k = vf_mul(vf_mul(vf_set1(2.0f), vf_mul(ea, eb)), vf_mul(ca, cb));
    return vf_mul(k, vf_add(vf_div(vf_set1(1.0f), vf_mul(s, s)), vf_div(vf_set1(1.0f), vf_mul(p, p))));
}

/* The half vector of two unit directions on the same side (z > 0), and
 * the cosine of either with it, |a + b| / 2: as a dot product, a . h
 * cancels for nearly opposite grazing directions (4e-4 relative error) and
 * differs from b . h, so f(a, b) would not equal f(b, a). */
static inline bsdf_v3 half_vector(bsdf_v3 a, bsdf_v3 b, vfloat *cos_d)
{
    bsdf_v3 h = {vf_add(a.x, b.x), vf_add(a.y, b.y), vf_add(a.z, b.z)};
    vfloat len = vf_sqrt(vf_fmadd(h.x, h.x, vf_fmadd(h.y, h.y, vf_mul(h.z, h.z))));
    vfloat inv = vf_div(vf_set1(1.0f), len);
    *cos_d = vf_mul(vf_set1(0.5f), len);
    return (bsdf_v3){vf_mul(h.x, inv), vf_mul(h.y, inv), vf_mul(h.z, inv)};
}

static inline vfloat dot3(bsdf_v3 a, bsdf_v3 b) { return vf_fmadd(a.x, b.x, vf_fmadd(a.y, b.y, vf_mul(a.z, b.z))); }

/* a b + c with the product exact, so that where the two cancel the result
 * keeps its digits: the fused multiply-add where the set has FMA, else
 * Dekker's exact product a b = p + e from Veltkamp's split of each factor
 * into halves of 12 bits (their products exact in float), p + c exact
 * where it cancels (Sterbenz), then e added: about one rounding of the
 * result either way. (-ffp-contract=off keeps the compiler from fusing.) */
static inline vfloat split_hi(vfloat x)
{
    vfloat t = vf_mul(vf_set1(4097.0f), x);
    return vf_sub(t, vf_sub(t, x));
}

static inline vfloat fmadd_exact(vfloat a, vfloat b, vfloat c)
{
#ifdef __FMA__
    return vf_fmadd(a, b, c);
#else
    vfloat p = vf_mul(a, b);
    vfloat ah = split_hi(a), bh = split_hi(b), al = vf_sub(a, ah), bl = vf_sub(b, bh);
    vfloat e = vf_add(vf_add(vf_add(vf_sub(vf_mul(ah, bh), p), vf_mul(ah, bl)), vf_mul(al, bh)), vf_mul(al, bl));
    return vf_add(vf_add(p, c), e);
#endif
}

/* Two-sided kinds: both directions mirrored when wo is below. */
static inline void to_upper_side(bsdf_v3 *wo, bsdf_v3 *wi)
{
    vmask below = vf_lt(wo->z, vf_zero());
    wo->z = vf_select(below, vf_neg(wo->z), wo->z);
    wi->z = vf_select(below, vf_neg(wi->z), wi->z);
}

/* The GGX reflection lobe with Fresnel weights fr (per channel; at the
 * half vector's angle): f, and its sampling pdf. wo.z, wi.z > 0. */
typedef struct {
    bsdf_v3 f;
    vfloat pdf;
} lobe_value;

static inline lobe_value ggx_reflection(vfloat a2, const float f0[3], bsdf_v3 wo, bsdf_v3 wi)
{
    vfloat c;
    bsdf_v3 h = half_vector(wo, wi, &c);
    vfloat d = ggx_d(a2, h);
    vfloat g = vf_mul(ggx_g1(a2, wo.z), ggx_g1(a2, wi.z));
    vfloat common = vf_div(vf_mul(d, g), vf_mul(vf_set1(4.0f), vf_mul(wo.z, wi.z)));
    lobe_value v;
    v.f.x = vf_mul(common, schlick(vf_set1(f0[0]), c));
    v.f.y = vf_mul(common, schlick(vf_set1(f0[1]), c));
    v.f.z = vf_mul(common, schlick(vf_set1(f0[2]), c));
    v.pdf = vf_div(vf_mul(d, h.z), vf_mul(vf_set1(4.0f), c));
    return v;
}

/* A GGX microfacet normal (z >= 0) drawn from D(h) cos(theta_h). */
static inline bsdf_v3 ggx_sample_h(vfloat a2, vfloat u1, vfloat u2)
{
    vfloat one = vf_set1(1.0f);
    vfloat cos2 = vf_div(vf_sub(one, u1), vf_fmadd(vf_sub(a2, one), u1, one));
    vfloat cos_t = vf_sqrt(cos2), sin_t = vf_sqrt(vf_max(vf_sub(one, cos2), vf_zero()));
    vfloat phi = vf_mul(vf_set1(2.0f * BSDF_PI), u2);
    return (bsdf_v3){vf_mul(sin_t, vf_cos(phi)), vf_mul(sin_t, vf_sin(phi)), cos_t};
}

/* A direction drawn from the GGX lobe for wo (wo.z > 0): the microfacet
 * normal from D(h) cos(theta_h), wo reflected about it. */
static inline bsdf_v3 ggx_sample_wi(vfloat a2, bsdf_v3 wo, vfloat u1, vfloat u2)
{
    bsdf_v3 h = ggx_sample_h(a2, u1, u2);
    vfloat c2 = vf_mul(vf_set1(2.0f), dot3(wo, h));
    bsdf_v3 wi = {vf_fmsub(c2, h.x, wo.x), vf_fmsub(c2, h.y, wo.y), vf_fmsub(c2, h.z, wo.z)};
    /* renormalized: the reflection's rounding (|wi| off by up to 1e-6)
     * would move a sharp lobe's pdf at wi by 1e-7 / alpha relative */
    vfloat inv = vf_div(vf_set1(1.0f), vf_sqrt(dot3(wi, wi)));
    return (bsdf_v3){vf_mul(wi.x, inv), vf_mul(wi.y, inv), vf_mul(wi.z, inv)};
}

static inline bsdf_v3 cosine_sample_wi(vfloat u1, vfloat u2)
{
    vfloat r = vf_sqrt(u1), phi = vf_mul(vf_set1(2.0f * BSDF_PI), u2);
    return (bsdf_v3){vf_mul(r, vf_cos(phi)), vf_mul(r, vf_sin(phi)),
                     vf_sqrt(vf_max(vf_sub(vf_set1(1.0f), u1), vf_zero()))};
}

/* Rough glass (Walter, Marschner, Li, Torrance 2007): GGX microfacets on
 * a dielectric, +z outside (index 1), -z inside (index ior), wo and wi on
 * any sides. With eta_o and eta_i the indices on wo's and wi's sides, F the
 * Fresnel reflectance for light on wo's side at the microfacet and
 * G = G1(wo) G1(wi) (Smith, separable), directions on the same side reflect
 * about h = normalize(wo + wi) (turned to +z):
 *   f = F D(h) G / (4 |wo.z| |wi.z|),  pdf = F D(h) h.z / (4 |wo . h|);
 * on opposite sides they refract about the generalized half vector
 * h = -(eta_o wo + eta_i wi) / |eta_o wo + eta_i wi| (turned to +z), when
 * each also lies on its own side of the microfacet (wo . h has the sign of
 * wo.z, wi . h that of wi.z; else f = 0):
 *   f = |wo . h| |wi . h| eta_i^2 (1 - F) D(h) G / (|wo.z| |wi.z| (eta_o wo . h + eta_i wi . h)^2),
 *   pdf = (1 - F) D(h) h.z eta_i^2 |wi . h| / (eta_o wo . h + eta_i wi . h)^2,
 * the pdf being D(h) h.z, the probability of the lobe and the Jacobian of
 * h's map to wi (the paper's eqs. 14, 17). f is the paper's eq. 21 with
 * eta_i^2 where it has eta_o^2: like LANES_BSDF_GLASS it leaves out the
 * factor (eta_o / eta_i)^2 by which radiance changes across the boundary
 * (it cancels on a path that enters and leaves a closed object). So the
 * reflection is reciprocal, f(wo, wi) = f(wi, wo), but the transmission
 * obeys f(wo, wi) eta_o^2 = f(wi, wo) eta_i^2: it is the physical BTDF
 * with its arguments swapped. The sample weight f cos / pdf is then
 * G |wo . h| / (|wo.z| h.z) in either lobe, tinted, and its mean is at most
 * 1. Multiplied by the tint (each lane's albedo).
 *
 * Guarded as the opaque lobes: D from h's x and y (ggx_d); reflection's
 * cosine |wo + wi| / 2 (half_vector); the transmission's denominator, a
 * sum of terms of opposite signs, as |eta_o wo + eta_i wi|^2, which it
 * equals; each component of that vector, ior w_in + w_out (w_in the
 * direction inside), with the product exact (fmadd_exact), so it keeps its
 * digits where the terms cancel: at the lobe's peak, where D needs them
 * (ior near 1 magnifies the loss by 1 / |ior - 1|), and where a microfacet
 * is grazing, where |wo . h| is small (a product rounded the usual way
 * left 7e-4 relative error in the pdf at |wo . h| = 1.5e-5); 1 - F from
 * both cosines (dielectric_transmittance). Lanes with wo.z or wi.z 0, or a
 * configuration no microfacet explains (h undefined, a direction behind
 * its facet), give f = 0 and pdf = 0; so does the transmission of an
 * index-matched surface (LANES_BSDF_MIN_IOR_GAP). */
static inline lobe_value rough_glass_eval(const lanes_bsdf *b, bsdf_v3 tint, bsdf_v3 wo, bsdf_v3 wi)
{
    const vfloat zero = vf_zero(), one = vf_set1(1.0f), ior = vf_set1(b->ior);
    const vfloat a2 = bsdf_alpha2(b);
    vmask o_up = vf_gt(wo.z, zero), o_down = vf_lt(wo.z, zero);
    vmask i_up = vf_gt(wi.z, zero), i_down = vf_lt(wi.z, zero);
    vmask reflect = vm_or(vm_and(o_up, i_up), vm_and(o_down, i_down));
    vmask refract = vm_or(vm_and(o_up, i_down), vm_and(o_down, i_up));
    vfloat co = vf_abs(wo.z), ci = vf_abs(wi.z);
    /* the index on wo's side, and on the other */
    vfloat eta_o = vf_select(o_down, ior, one), eta_x = vf_select(o_down, one, ior);
    vfloat g = vf_div(vf_mul(ggx_g1(a2, co), ggx_g1(a2, ci)), vf_mul(co, ci)); /* G / (|wo.z| |wi.z|) */

    /* reflection, as seen from above */
    vfloat cr, unused;
    bsdf_v3 hr = half_vector((bsdf_v3){wo.x, wo.y, co}, (bsdf_v3){wi.x, wi.y, ci}, &cr);
    vfloat dr = vf_mul(dielectric_fresnel(cr, eta_o, eta_x, &unused), ggx_d(a2, hr));
    vfloat f_r = vf_mul(vf_mul(vf_set1(0.25f), dr), g);
    vfloat pdf_r = vf_div(vf_mul(dr, hr.z), vf_mul(vf_set1(4.0f), cr));

    /* refraction */
    bsdf_v3 w_in = {vf_select(o_down, wo.x, wi.x), vf_select(o_down, wo.y, wi.y), vf_select(o_down, wo.z, wi.z)};
    bsdf_v3 w_out = {vf_select(o_down, wi.x, wo.x), vf_select(o_down, wi.y, wo.y), vf_select(o_down, wi.z, wo.z)};
    bsdf_v3 hv = {fmadd_exact(ior, w_in.x, w_out.x), fmadd_exact(ior, w_in.y, w_out.y),
                  fmadd_exact(ior, w_in.z, w_out.z)};
    vfloat len2 = dot3(hv, hv);
    vfloat inv = vf_div(one, vf_sqrt(len2));
    inv = vf_select(vf_lt(hv.z, zero), vf_neg(inv), inv);
    bsdf_v3 ht = {vf_mul(hv.x, inv), vf_mul(hv.y, inv), vf_mul(hv.z, inv)};
    vfloat dot_o = dot3(wo, ht), dot_i = dot3(wi, ht);
    vmask facing = vm_and(vf_gt(vf_select(o_down, vf_neg(dot_o), dot_o), zero),
                          vf_gt(vf_select(o_down, dot_i, vf_neg(dot_i)), zero));
    refract = vm_and(refract, vm_and(facing, vf_gt(len2, zero)));
    const float gap = b->ior - 1.0f;
    if (gap < LANES_BSDF_MIN_IOR_GAP && gap > -LANES_BSDF_MIN_IOR_GAP) refract = vm_false();
    vfloat ao = vf_abs(dot_o), ai = vf_abs(dot_i);
    vfloat jac = vf_div(vf_mul(vf_mul(eta_x, eta_x), ai), len2); /* eta_i^2 |wi . h| / |..|^2 */
    vfloat dt = vf_mul(vf_mul(dielectric_transmittance(ao, ai, eta_o, eta_x), ggx_d(a2, ht)), jac);
    vfloat f_t = vf_mul(vf_mul(dt, ao), g);
    vfloat pdf_t = vf_mul(dt, ht.z);

    vfloat f = vf_select(reflect, f_r, vf_select(refract, f_t, zero));
    lobe_value v;
    v.pdf = vf_select(reflect, pdf_r, vf_select(refract, pdf_t, zero));
    v.f = (bsdf_v3){vf_mul(f, tint.x), vf_mul(f, tint.y), vf_mul(f, tint.z)};
    return v;
}

/* A rough glass direction for wo: a microfacet normal m from
 * D(m) cos(theta_m), turned to wo's side; reflection about it with the
 * Fresnel probability F(wo . m) (1 under total internal reflection), else
 * refraction through it. Lanes whose m faces away from wo, or whose
 * direction lands on the wrong side of the surface, are not valid (the pdf
 * of rough_glass_eval counts only the rest). Weight f cos / pdf from
 * rough_glass_eval at the direction made. */
static inline bsdf_sample_result rough_glass_sample(const lanes_bsdf *b, bsdf_v3 tint, bsdf_v3 wo, vfloat u1,
                                                    vfloat u2, vfloat u3)
{
    const vfloat zero = vf_zero(), one = vf_set1(1.0f), ior = vf_set1(b->ior);
    vmask outside = vf_gt(wo.z, zero);
    vfloat side = vf_select(outside, one, vf_set1(-1.0f));
    bsdf_v3 m = ggx_sample_h(bsdf_alpha2(b), u1, u2);
    m = (bsdf_v3){vf_mul(side, m.x), vf_mul(side, m.y), vf_mul(side, m.z)};
    vfloat c = dot3(wo, m), ct;
    vfloat eta_o = vf_select(outside, one, ior), eta_x = vf_select(outside, ior, one);
    vfloat fr = dielectric_fresnel(vf_max(c, zero), eta_o, eta_x, &ct);
    vmask reflect = vf_lt(u3, fr);
    /* reflected 2 c m - wo, refracted (eta c - ct) m - eta wo */
    vfloat eta = vf_div(eta_o, eta_x);
    vfloat km = vf_select(reflect, vf_add(c, c), vf_fmsub(eta, c, ct)), kw = vf_select(reflect, one, eta);
    bsdf_v3 wi = {vf_fmsub(km, m.x, vf_mul(kw, wo.x)), vf_fmsub(km, m.y, vf_mul(kw, wo.y)),
                  vf_fmsub(km, m.z, vf_mul(kw, wo.z))};
    vfloat inv = vf_div(one, vf_sqrt(dot3(wi, wi)));
    wi = (bsdf_v3){vf_mul(wi.x, inv), vf_mul(wi.y, inv), vf_mul(wi.z, inv)};
    lobe_value v = rough_glass_eval(b, tint, wo, wi);
    vmask up = vf_gt(wi.z, zero), down = vf_lt(wi.z, zero);
    vmask same = vm_or(vm_and(outside, up), vm_andnot(down, outside));
    vmask other = vm_or(vm_and(outside, down), vm_andnot(up, outside));
    vmask lobe_ok = vm_or(vm_and(reflect, same), vm_andnot(other, reflect));
    bsdf_sample_result r;
    r.valid = vm_and(vm_and(vf_gt(c, zero), vf_gt(v.pdf, zero)), lobe_ok);
    r.delta = vm_false();
    vfloat k = vf_div(vf_abs(wi.z), v.pdf);
    r.weight = (bsdf_v3){vf_select(r.valid, vf_mul(v.f.x, k), zero), vf_select(r.valid, vf_mul(v.f.y, k), zero),
                         vf_select(r.valid, vf_mul(v.f.z, k), zero)};
    r.pdf = vf_select(r.valid, v.pdf, zero);
    r.wi = wi;
    return r;
}

/* The material's albedo on every lane, for a call without a texture. */
static inline bsdf_v3 bsdf_uniform_albedo(const lanes_bsdf *b)
{
    return (bsdf_v3){vf_set1(b->albedo[0]), vf_set1(b->albedo[1]), vf_set1(b->albedo[2])};
}

/* f and pdf for wo, wi (any sides), with the albedo of each lane (a
 * texture's, or b's own): Lambert's, plastic's base, the specular tints. */
static inline lobe_value bsdf_eval(const lanes_bsdf *b, bsdf_v3 albedo, bsdf_v3 wo, bsdf_v3 wi)
{
    lobe_value v = {{vf_zero(), vf_zero(), vf_zero()}, vf_zero()};
    if (b->kind == LANES_BSDF_MIRROR || b->kind == LANES_BSDF_GLASS) return v;
    if (b->kind == LANES_BSDF_ROUGH_GLASS) return rough_glass_eval(b, albedo, wo, wi);
    to_upper_side(&wo, &wi);
    vmask ok = vm_and(vf_gt(wo.z, vf_zero()), vf_gt(wi.z, vf_zero()));
    const vfloat inv_pi = vf_set1(1.0f / BSDF_PI);
    switch (b->kind) {
    case LANES_BSDF_LAMBERT:
        v.f = (bsdf_v3){vf_mul(albedo.x, inv_pi), vf_mul(albedo.y, inv_pi), vf_mul(albedo.z, inv_pi)};
        v.pdf = vf_mul(wi.z, inv_pi);
        break;
    case LANES_BSDF_CONDUCTOR:
        v = ggx_reflection(bsdf_alpha2(b), b->f0, wo, wi);
        break;
    case LANES_BSDF_PLASTIC: {
        const float coat[3] = {LANES_BSDF_COAT_F0, LANES_BSDF_COAT_F0, LANES_BSDF_COAT_F0};
        lobe_value s = ggx_reflection(bsdf_alpha2(b), coat, wo, wi);
        /* light through the coat both ways, by its Fresnel transmittance
         * at each direction: symmetric in wo and wi */
        vfloat f0 = vf_set1(LANES_BSDF_COAT_F0), one = vf_set1(1.0f);
        vfloat t = vf_mul(vf_mul(vf_sub(one, schlick(f0, wo.z)), vf_sub(one, schlick(f0, wi.z))), inv_pi);
        v.f = (bsdf_v3){vf_fmadd(t, albedo.x, s.f.x), vf_fmadd(t, albedo.y, s.f.y), vf_fmadd(t, albedo.z, s.f.z)};
        const float pick = LANES_BSDF_COAT_PICK;
        v.pdf = vf_fmadd(vf_set1(pick), s.pdf, vf_mul(vf_set1((1.0f - pick) / BSDF_PI), wi.z));
        break;
    }
    default:
        break;
    }
    v.f.x = vf_select(ok, v.f.x, vf_zero());
    v.f.y = vf_select(ok, v.f.y, vf_zero());
    v.f.z = vf_select(ok, v.f.z, vf_zero());
    v.pdf = vf_select(ok, v.pdf, vf_zero());
    return v;
}

/* A scattered direction for wo from (u1, u2, u3) in [0, 1)^3, with each
 * lane's albedo as in bsdf_eval. */
static inline bsdf_sample_result bsdf_sample(const lanes_bsdf *b, bsdf_v3 albedo, bsdf_v3 wo, vfloat u1, vfloat u2,
                                             vfloat u3)
{
    bsdf_sample_result r;
    const vfloat zero = vf_zero(), one = vf_set1(1.0f);
    const bsdf_v3 tint = albedo;
    r.delta = b->kind == LANES_BSDF_MIRROR || b->kind == LANES_BSDF_GLASS ? vm_true() : vm_false();
    r.pdf = zero;
    if (b->kind == LANES_BSDF_MIRROR) {
        r.wi = (bsdf_v3){vf_neg(wo.x), vf_neg(wo.y), wo.z};
        r.weight = tint;
        r.valid = vf_neq(wo.z, zero);
        return r;
    }
    if (b->kind == LANES_BSDF_GLASS) {
        /* Reflection with the Fresnel probability, so either way the weight
         * is the tint. It leaves out the (eta_i / eta_t)^2 by which radiance
         * changes across the boundary: that cancels on a path that enters
         * and leaves a closed object. */
        vmask outside = vf_gt(wo.z, zero);
        vfloat eta_i = vf_select(outside, one, vf_set1(b->ior)), eta_t = vf_select(outside, vf_set1(b->ior), one);
        vfloat ci = vf_abs(wo.z), ct;
        vfloat fr = dielectric_fresnel(ci, eta_i, eta_t, &ct);
        vmask reflect = vf_lt(u3, fr);
        vfloat eta = vf_div(eta_i, eta_t);
        /* refracted: -eta wo + (eta ci - ct) n, n on wo's side */
        vfloat side = vf_select(outside, one, vf_set1(-1.0f));
        vfloat tz = vf_mul(vf_neg(ct), side);
        r.wi.x = vf_select(reflect, vf_neg(wo.x), vf_mul(vf_neg(eta), wo.x));
        r.wi.y = vf_select(reflect, vf_neg(wo.y), vf_mul(vf_neg(eta), wo.y));
        r.wi.z = vf_select(reflect, wo.z, tz);
        r.weight = tint;
        r.valid = vf_neq(wo.z, zero);
        return r;
    }
    if (b->kind == LANES_BSDF_ROUGH_GLASS) return rough_glass_sample(b, tint, wo, u1, u2, u3);
    /* opaque kinds: work above the surface, mirror back at the end */
    vmask below = vf_lt(wo.z, zero);
    bsdf_v3 up = {wo.x, wo.y, vf_abs(wo.z)};
    bsdf_v3 wi;
    if (b->kind == LANES_BSDF_LAMBERT) {
        wi = cosine_sample_wi(u1, u2);
    } else if (b->kind == LANES_BSDF_CONDUCTOR) {
        wi = ggx_sample_wi(bsdf_alpha2(b), up, u1, u2);
    } else {
        vmask coat = vf_lt(u3, vf_set1(LANES_BSDF_COAT_PICK));
        bsdf_v3 s = ggx_sample_wi(bsdf_alpha2(b), up, u1, u2), d = cosine_sample_wi(u1, u2);
        wi = (bsdf_v3){vf_select(coat, s.x, d.x), vf_select(coat, s.y, d.y), vf_select(coat, s.z, d.z)};
    }
    lobe_value v = bsdf_eval(b, albedo, up, wi);
    r.valid = vm_and(vf_gt(wi.z, zero), vf_gt(v.pdf, zero));
    vfloat k = vf_select(r.valid, vf_div(wi.z, v.pdf), zero);
    r.weight = (bsdf_v3){vf_mul(v.f.x, k), vf_mul(v.f.y, k), vf_mul(v.f.z, k)};
    r.pdf = vf_select(r.valid, v.pdf, zero);
    r.wi = (bsdf_v3){wi.x, wi.y, vf_select(below, vf_neg(wi.z), wi.z)};
    return r;
}

#endif
