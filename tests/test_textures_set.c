/* trace/kernels/texture_core.h over arrays, at one kernel set (see test_textures.h). */
#include "simd/simd.h"
#include "test_textures.h"
#include "trace/kernels/texture_core.h"

void LANES_FN(test_noise)(size_t n, const float *x, const float *y, const float *z, float *out)
{
    for (size_t i = 0; i < n; i += LANES_W) vf_storeu(out + i, vf_noise3(vf_loadu(x + i), vf_loadu(y + i), vf_loadu(z + i)));
}

void LANES_FN(test_texture)(const lanes_texture *t, size_t n, const float *x, const float *y, const float *z,
                            float *weight, float *color)
{
    for (size_t i = 0; i < n; i += LANES_W) {
        bsdf_v3 p = {vf_loadu(x + i), vf_loadu(y + i), vf_loadu(z + i)};
        vf_storeu(weight + i, texture_weight(t, p));
        bsdf_v3 c = texture_color(t, p);
        vf_storeu(color + i, c.x);
        vf_storeu(color + n + i, c.y);
        vf_storeu(color + 2 * n + i, c.z);
    }
}
