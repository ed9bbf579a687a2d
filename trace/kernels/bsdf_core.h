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
 * 2007), which gives the pdf in closed form. tests/test_bsdf.c checks all
 * of it against double-precision references.
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

/* A direction drawn from the GGX lobe for wo (wo.z > 0): the microfacet
 * normal from D(h) cos(theta_h), wo reflected about it. */
static inline bsdf_v3 ggx_sample_wi(vfloat a2, bsdf_v3 wo, vfloat u1, vfloat u2)
{
    vfloat one = vf_set1(1.0f);
    vfloat cos2 = vf_div(vf_sub(one, u1), vf_fmadd(vf_sub(a2, one), u1, one));
    vfloat cos_t = vf_sqrt(cos2), sin_t = vf_sqrt(vf_max(vf_sub(one, cos2), vf_zero()));
    vfloat phi = vf_mul(vf_set1(2.0f * BSDF_PI), u2);
    bsdf_v3 h = {vf_mul(sin_t, vf_cos(phi)), vf_mul(sin_t, vf_sin(phi)), cos_t};
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
