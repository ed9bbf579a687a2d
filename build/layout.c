/* Allocation of the kernels' SoA arrays (build/layout.h).
 *
 * Compiled for the x86-64 baseline. */
#include "build/layout.h"

#include "build/bvh_alloc.h"

#include <stdlib.h>
#include <string.h>

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
        lanes_prefault(*arrays[i], cap * sizeof(float));
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
