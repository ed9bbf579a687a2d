/* A surface's scattering, as the shaders see it: the kind and its
 * parameters, uniform over a shading batch (one material). Plain C, shared
 * by the baseline code that fills it from a material and the per-set
 * shaders (trace/kernels/bsdf_core.h) that evaluate and sample it.
 *
 * Directions are in the shading frame: the geometric normal is +z, wo
 * points back along the incoming ray, wi towards where light comes from;
 * both unit length. */
#ifndef LANES_TRACE_BSDF_H
#define LANES_TRACE_BSDF_H

typedef enum lanes_bsdf_kind {
    LANES_BSDF_LAMBERT = 0, /* albedo / pi */
    LANES_BSDF_MIRROR,      /* perfect reflection, tinted by albedo */
    LANES_BSDF_CONDUCTOR,   /* GGX microfacets, Schlick's Fresnel from f0 (per channel) */
    LANES_BSDF_PLASTIC,     /* Lambert (albedo) under a GGX dielectric coat of ior 1.5 */
    LANES_BSDF_GLASS,       /* smooth dielectric of index ior: Fresnel reflection or refraction, tinted */
    LANES_BSDF_ROUGH_GLASS  /* GGX microfacet dielectric of index ior (Walter et al. 2007): rough
                             * reflection and refraction, tinted; not a delta lobe */
} lanes_bsdf_kind;

typedef struct lanes_bsdf {
    lanes_bsdf_kind kind;
    float albedo[3];  /* in [0, 1] */
    float roughness;  /* in [0, 1]; GGX alpha = roughness^2, at least LANES_BSDF_MIN_ALPHA */
    float f0[3];      /* conductor: reflectance at normal incidence, in [0, 1] */
    float ior;        /* glass, rough glass: > 0, the inside's index over the outside's (+z is outside) */
} lanes_bsdf;

/* Below this alpha GGX's peak, 1 / (pi alpha^2), leaves float's comfort
 * (and the surface is a mirror to any renderer's eye). */
#define LANES_BSDF_MIN_ALPHA 1e-3f

/* Rough glass with |ior - 1| below this is index-matched: its transmission
 * would be a delta lobe (straight through), narrower than float resolves
 * (at ior 1 + 1 ulp the sampler's mean weight came out 1.06), so it has
 * none: f = pdf = 0 on opposite sides. */
#define LANES_BSDF_MIN_IOR_GAP 1e-4f

/* The coat's reflectance at normal incidence (ior 1.5: ((1.5 - 1) / 2.5)^2). */
#define LANES_BSDF_COAT_F0 0.04f

/* bsdf_sample's flags per direction: a direction was made; it is a delta
 * lobe's (its weight replaces f cos / pdf, and its pdf is 0). */
enum { LANES_BSDF_VALID = 1, LANES_BSDF_DELTA = 2 };

/* The probability that a plastic sample takes the coat's lobe (else the
 * diffuse base); the pdf is the mixture, so any value in (0, 1) is right. */
#define LANES_BSDF_COAT_PICK 0.5f

#endif
