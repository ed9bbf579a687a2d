/* The shaders' building blocks over arrays, compiled per set: BSDF values
 * and samples (bsdf_core.h), solid textures and noise (texture_core.h), on
 * n points or directions in SoA form (component k of item i at
 * p[k * n + i]), SIMD across the items; any n, the tail under a mask.
 * Parameters are uniform over a call, one material per shading batch, but
 * for the albedo: a textured material passes each item's (SoA), else NULL. */
#include "trace/kernels/bsdf_core.h"
#include "trace/kernels/kernel_common.h"
#include "trace/kernels/kernel_decls.h"
#include "trace/kernels/texture_core.h"

static inline vfloat load_part(const float *p, size_t i, size_t n)
{
    return n - i >= LANES_W ? vf_loadu(p + i) : vf_load_masked(vm_first_n(n - i), p + i);
}

static inline void store_part(float *p, size_t i, size_t n, vfloat v)
{
    if (n - i >= LANES_W)
        vf_storeu(p + i, v);
    else
        vf_store_masked(p + i, vm_first_n(n - i), v);
}

static inline bsdf_v3 load3(const float *p, size_t i, size_t n)
{
    return (bsdf_v3){load_part(p, i, n), load_part(p + n, i, n), load_part(p + 2 * n, i, n)};
}

static inline void store3(float *p, size_t i, size_t n, bsdf_v3 v)
{
    store_part(p, i, n, v.x);
    store_part(p + n, i, n, v.y);
    store_part(p + 2 * n, i, n, v.z);
}

static inline bsdf_v3 albedo_at(const lanes_bsdf *b, const float *albedo, size_t i, size_t n)
{
    return albedo ? load3(albedo, i, n) : bsdf_uniform_albedo(b);
}

void LANES_FN(lanes_bsdf_eval)(const lanes_bsdf *b, size_t n, const float *albedo, const float *wo, const float *wi,
                               float *f, float *pdf)
{
    for (size_t i = 0; i < n; i += LANES_W) {
        lobe_value v = bsdf_eval(b, albedo_at(b, albedo, i, n), load3(wo, i, n), load3(wi, i, n));
        store3(f, i, n, v.f);
        store_part(pdf, i, n, v.pdf);
    }
}

void LANES_FN(lanes_bsdf_sample)(const lanes_bsdf *b, size_t n, const float *albedo, const float *wo, const float *u,
                                 float *wi, float *weight, float *pdf, uint8_t *flags)
{
    for (size_t i = 0; i < n; i += LANES_W) {
        bsdf_v3 uu = load3(u, i, n);
        bsdf_sample_result r = bsdf_sample(b, albedo_at(b, albedo, i, n), load3(wo, i, n), uu.x, uu.y, uu.z);
        store3(wi, i, n, r.wi);
        store3(weight, i, n, r.weight);
        store_part(pdf, i, n, r.pdf);
        uint32_t valid = vm_bits(r.valid), delta = vm_bits(r.delta);
        for (size_t k = 0; k < LANES_W && i + k < n; k++)
            flags[i + k] = (uint8_t)(((valid >> k) & 1u) * LANES_BSDF_VALID | ((delta >> k) & 1u) * LANES_BSDF_DELTA);
    }
}

void LANES_FN(lanes_texture_color)(const lanes_texture *t, size_t n, const float *p, float *weight, float *color)
{
    for (size_t i = 0; i < n; i += LANES_W) {
        bsdf_v3 q = load3(p, i, n);
        store_part(weight, i, n, texture_weight(t, q));
        store3(color, i, n, texture_color(t, q));
    }
}

void LANES_FN(lanes_noise)(size_t n, const float *p, float *out)
{
    for (size_t i = 0; i < n; i += LANES_W) {
        bsdf_v3 q = load3(p, i, n);
        store_part(out, i, n, vf_noise3(q.x, q.y, q.z));
    }
}
