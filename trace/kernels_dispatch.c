/* The tables of the kernel sets compiled into this build, and the lookup
 * of the active one. Also the baseline
 * helpers for the kernels' data (allocation, scalar ray set-up). */
#include "trace/kernels.h"

#include "simd/vec1_scalar.h" /* baseline: SSE is part of x86-64 */

#include <float.h>
#include <math.h>
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

/* count rounded up to LANES_MAX_W plus LANES_MAX_W elements of slack, so a
 * full-width load starting at any element below count stays inside; 0 when
 * the size is absurd. */
static size_t padded(size_t count)
{
    const size_t limit = ((size_t)1 << 40) / sizeof(float); /* 1 TiB per array */
    if (count > limit) return 0;
    return (count + LANES_MAX_W - 1) / LANES_MAX_W * LANES_MAX_W + LANES_MAX_W;
}

/* Allocates n float arrays of one padded size, zero-filled so that the
 * padding lanes hold defined values. */
static bool alloc_arrays(float **arrays[], int n, size_t count, size_t *capacity)
{
    size_t cap = padded(count);
    if (cap == 0) return false;
    for (int i = 0; i < n; i++) *arrays[i] = NULL;
    for (int i = 0; i < n; i++) {
        *arrays[i] = aligned_alloc(LANES_ALIGN, cap * sizeof(float));
        if (!*arrays[i]) {
            for (int j = 0; j < i; j++) free(*arrays[j]), *arrays[j] = NULL;
            return false;
        }
        memset(*arrays[i], 0, cap * sizeof(float));
    }
    *capacity = cap;
    return true;
}

static void free_arrays(float **arrays[], int n)
{
    for (int i = 0; i < n; i++) free(*arrays[i]), *arrays[i] = NULL;
}

#define RAY_ARRAYS(r)                                                                      \
    float **arrays[] = {&(r)->ox, &(r)->oy, &(r)->oz, &(r)->dx,  &(r)->dy,    &(r)->dz,    \
                        &(r)->rdx, &(r)->rdy, &(r)->rdz, &(r)->tnear, &(r)->tfar}
#define BOX_ARRAYS(b)                                                                      \
    float **arrays[] = {&(b)->minx, &(b)->miny, &(b)->minz, &(b)->maxx, &(b)->maxy, &(b)->maxz}
#define TRI_ARRAYS(t)                                                                      \
    float **arrays[] = {&(t)->v0x, &(t)->v0y, &(t)->v0z, &(t)->v1x, &(t)->v1y,             \
                        &(t)->v1z, &(t)->v2x, &(t)->v2y, &(t)->v2z}
#define HIT_ARRAYS(h) float **arrays[] = {&(h)->t, &(h)->u, &(h)->v}
#define COUNT_OF(a) ((int)(sizeof(a) / sizeof((a)[0])))

bool lanes_rays_alloc(lanes_rays *r, size_t count)
{
    RAY_ARRAYS(r);
    r->count = count;
    return alloc_arrays(arrays, COUNT_OF(arrays), count, &r->capacity);
}
void lanes_rays_free(lanes_rays *r)
{
    RAY_ARRAYS(r);
    free_arrays(arrays, COUNT_OF(arrays));
    r->count = r->capacity = 0;
}
bool lanes_boxes_alloc(lanes_boxes *b, size_t count)
{
    BOX_ARRAYS(b);
    b->count = count;
    return alloc_arrays(arrays, COUNT_OF(arrays), count, &b->capacity);
}
void lanes_boxes_free(lanes_boxes *b)
{
    BOX_ARRAYS(b);
    free_arrays(arrays, COUNT_OF(arrays));
    b->count = b->capacity = 0;
}
bool lanes_triangles_alloc(lanes_triangles *t, size_t count)
{
    TRI_ARRAYS(t);
    t->count = count;
    return alloc_arrays(arrays, COUNT_OF(arrays), count, &t->capacity);
}
void lanes_triangles_free(lanes_triangles *t)
{
    TRI_ARRAYS(t);
    free_arrays(arrays, COUNT_OF(arrays));
    t->count = t->capacity = 0;
}
bool lanes_tri_hits_alloc(lanes_tri_hits *h, size_t count)
{
    HIT_ARRAYS(h);
    size_t cap;
    return alloc_arrays(arrays, COUNT_OF(arrays), count, &cap);
}
void lanes_tri_hits_free(lanes_tri_hits *h)
{
    HIT_ARRAYS(h);
    free_arrays(arrays, COUNT_OF(arrays));
}
