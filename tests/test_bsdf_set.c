/* trace/kernels/bsdf_core.h over arrays, at one kernel set (see test_bsdf.h). */
#include "simd/simd.h"
#include "test_bsdf.h"
#include "trace/kernels/bsdf_core.h"

static bsdf_v3 load3(const float *p, size_t n, size_t i)
{
    return (bsdf_v3){vf_loadu(p + i), vf_loadu(p + n + i), vf_loadu(p + 2 * n + i)};
}

static void store3(float *p, size_t n, size_t i, bsdf_v3 v)
{
    vf_storeu(p + i, v.x);
    vf_storeu(p + n + i, v.y);
    vf_storeu(p + 2 * n + i, v.z);
}

void LANES_FN(test_bsdf_eval)(const lanes_bsdf *b, size_t n, const float *wo, const float *wi, float *f, float *pdf)
{
    for (size_t i = 0; i < n; i += LANES_W) {
        lobe_value v = bsdf_eval(b, load3(wo, n, i), load3(wi, n, i));
        store3(f, n, i, v.f);
        vf_storeu(pdf + i, v.pdf);
    }
}

void LANES_FN(test_bsdf_sample)(const lanes_bsdf *b, size_t n, const float *wo, const float *u, float *wi,
                                float *weight, float *pdf, uint8_t *flags)
{
    for (size_t i = 0; i < n; i += LANES_W) {
        bsdf_v3 uu = load3(u, n, i);
        bsdf_sample_result r = bsdf_sample(b, load3(wo, n, i), uu.x, uu.y, uu.z);
        store3(wi, n, i, r.wi);
        store3(weight, n, i, r.weight);
        vf_storeu(pdf + i, r.pdf);
        uint32_t valid = vm_bits(r.valid), delta = vm_bits(r.delta);
        for (int k = 0; k < LANES_W; k++)
            flags[i + (size_t)k] = (uint8_t)(((valid >> k) & 1u) * TEST_BSDF_VALID | ((delta >> k) & 1u) * TEST_BSDF_DELTA);
    }
}
