/* The tables of the kernel sets compiled into this build, and the lookup
 * of the active one. Also the scalar ray set-up. */
#include "trace/kernels.h"

#include "simd/vec1_scalar.h" /* baseline: SSE is part of x86-64 */

#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

/* One table per set this build compiled (lanes_built_sets.h, generated). */
#include "lanes_built_sets.h"

#define DECLARE(id, name) extern const lanes_kernels lanes_kernels_##name;
LANES_BUILT_SETS(DECLARE)
#undef DECLARE

static const lanes_kernels *const tables[LANES_ISA_COUNT] = {
#define ENTRY(id, name) [LANES_ISA_##id] = &lanes_kernels_##name,
    LANES_BUILT_SETS(ENTRY)
#undef ENTRY
};

const lanes_kernels *lanes_kernels_for(lanes_isa isa)
{
    return isa >= 0 && isa < LANES_ISA_COUNT ? tables[isa] : NULL;
}

/* Each set's wide-BVH kernels for wider nodes (trace/kernels/wide_variant.h),
 * and the tables made from them: the set's own with those laid over. */
#define DECLARE(id, name)                                                                  \
    extern const lanes_wide_kernels lanes_wide_kernels_w8_##name, lanes_wide_kernels_w16_##name;
LANES_BUILT_SETS(DECLARE)
#undef DECLARE

enum { VARIANT_8, VARIANT_16, VARIANTS };
static const lanes_wide_kernels *const variants[LANES_ISA_COUNT][VARIANTS] = {
#define ENTRY(id, name) [LANES_ISA_##id] = {&lanes_wide_kernels_w8_##name, &lanes_wide_kernels_w16_##name},
    LANES_BUILT_SETS(ENTRY)
#undef ENTRY
};
static lanes_kernels by_width[LANES_ISA_COUNT][VARIANTS];
static pthread_once_t by_width_once = PTHREAD_ONCE_INIT;

static void make_by_width(void)
{
    for (int i = 0; i < LANES_ISA_COUNT; i++)
        for (int v = 0; v < VARIANTS; v++) {
            const lanes_wide_kernels *w = variants[i][v];
            if (!tables[i] || !w || w->width == 0) continue;
            lanes_kernels *k = &by_width[i][v];
            *k = *tables[i];
            k->wide_width = w->width;
#define LAY_OVER(kind, ret, name, params, args) k->name = w->name;
            LANES_KERNELS_WIDE_BVH(LAY_OVER)
#undef LAY_OVER
        }
}

const lanes_kernels *lanes_kernels_for_width(lanes_isa isa, int node_width)
{
    const lanes_kernels *k = lanes_kernels_for(isa);
    if (!k || k->wide_width == node_width) return k;
    int v = node_width == 8 ? VARIANT_8 : node_width == 16 ? VARIANT_16 : -1;
    if (v < 0) return NULL;
    pthread_once(&by_width_once, make_by_width);
    return by_width[isa][v].wide_width == node_width ? &by_width[isa][v] : NULL;
}

const lanes_kernels *lanes_kernels_current(void) { return tables[lanes_isa_current()]; }

/* The SSE estimate (12 bits) plus one Newton step; tiny components take the
 * exact 1/d, as in the kernels' fast mode (ray_kernels.c). The step is
 * written r (2 - d r) here and r + r (1 - d r) in the SIMD layer
 * (v1f_rcp_nr), so the two can differ in the last bit. */
static float fast_rcp(float d)
{
    if (fabsf(d) < 0x1p-60f) return 1.0f / d;
    float r = v1f_rcp_fast(d);
    return r * (2.0f - d * r);
}

bool lanes_ray_prepare_rcp(lanes_ray *ray, lanes_rcp_mode mode)
{
    bool ok = lanes_ray_prepare(ray);
    if (ok && mode == LANES_RCP_FAST)
        for (int a = 0; a < 3; a++) ray->rd[a] = fast_rcp(ray->d[a]);
    return ok;
}

bool lanes_ray_valid(const lanes_ray *ray)
{
    bool ok = !isnan(ray->tnear) && !isnan(ray->tfar);
    for (int a = 0; a < 3; a++) ok = ok && isfinite(ray->o[a]) && isfinite(ray->d[a]);
    return ok && (ray->d[0] != 0.0f || ray->d[1] != 0.0f || ray->d[2] != 0.0f);
}

bool lanes_ray_prepare(lanes_ray *ray)
{
    bool ok = lanes_ray_valid(ray);
    for (int a = 0; a < 3; a++) ray->rd[a] = 1.0f / ray->d[a];
    /* finite ends, as lanes_rays_prepare does (see ray_kernels.c) */
    if (ray->tnear < -FLT_MAX) ray->tnear = -FLT_MAX;
    if (ray->tfar > FLT_MAX) ray->tfar = FLT_MAX;
    if (!ok) {
        ray->tnear = INFINITY;
        ray->tfar = -INFINITY;
    }
    return ok;
}
