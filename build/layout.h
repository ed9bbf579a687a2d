/* The data the kernels read, as build/ lays it out and trace/ reads it:
 * rays, boxes, triangles and hits, one at a time and in structure-of-arrays
 * form, their padded allocation and their views. Below both build/ and
 * trace/ (it includes neither), so that neither includes the other.
 *
 * - Arrays are 64-byte aligned and padded (lanes_*_alloc): past the count
 *   they hold at least LANES_MAX_W more elements, so a full-width load that
 *   starts at any element below the count stays inside the allocation.
 * - Hit masks are bit arrays: bit i of word i/32 is ray (or primitive) i.
 *
 * Compiled for the x86-64 baseline: no intrinsics. */
#ifndef LANES_BUILD_LAYOUT_H
#define LANES_BUILD_LAYOUT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define LANES_MAX_W 16
#define LANES_ALIGN 64

/* Rays in structure-of-arrays form. */
typedef struct lanes_rays {
    float *ox, *oy, *oz;
    float *dx, *dy, *dz;
    float *rdx, *rdy, *rdz; /* 1/d, filled by lanes_rays_prepare */
    float *tnear, *tfar;
    size_t count;     /* rays in use */
    size_t capacity;  /* allocated elements per array */
} lanes_rays;

/* One ray, with its reciprocal direction (see lanes_ray_prepare). */
typedef struct lanes_ray {
    float o[3], d[3], rd[3];
    float tnear, tfar;
} lanes_ray;

typedef struct lanes_box {
    float min[3], max[3];
} lanes_box;

/* Boxes in structure-of-arrays form, the layout of a wide BVH node. */
typedef struct lanes_boxes {
    float *minx, *miny, *minz, *maxx, *maxy, *maxz;
    size_t count, capacity;
} lanes_boxes;

typedef struct lanes_triangle {
    float v0[3], v1[3], v2[3];
} lanes_triangle;

/* Triangles in structure-of-arrays form (the wide kernels load them
 * unaligned, so a view may start at any element). Vertices, not edges, are stored:
 * the watertight test needs each shared vertex transformed identically. */
typedef struct lanes_triangles {
    float *v0x, *v0y, *v0z, *v1x, *v1y, *v1z, *v2x, *v2y, *v2z;
    size_t count, capacity;
} lanes_triangles;

/* A triangle whose edge vectors have an exactly zero cross product
 * (repeated vertices, vertices on one axis-parallel line, ...) has no area
 * and is never hit: without this, rounding can give it a nonzero
 * determinant. The products of the cross product round alike when equal,
 * so an exact zero stays zero; a near-degenerate sliver is still tested.
 * Plain float operations (no contraction), so the wide BVH's build, which
 * replaces such triangles by NaN, and the kernels agree exactly. */
static inline bool lanes_triangle_no_area(const lanes_triangle *t)
{
    float e1[3], e2[3];
    for (int a = 0; a < 3; a++) e1[a] = t->v1[a] - t->v0[a], e2[a] = t->v2[a] - t->v0[a];
    return e1[1] * e2[2] - e1[2] * e2[1] == 0.0f && e1[2] * e2[0] - e1[0] * e2[2] == 0.0f &&
           e1[0] * e2[1] - e1[1] * e2[0] == 0.0f;
}

/* Results of the per-element triangle kernels. */
typedef struct lanes_tri_hits {
    float *t, *u, *v; /* u, v: barycentric weights of v1 and v2 */
} lanes_tri_hits;

/* Result of a closest-hit query. prim is the scene triangle index, or
 * LANES_NO_HIT; u, v are the barycentric weights of v1 and v2. */
#define LANES_NO_HIT 0xffffffffu
typedef struct lanes_hit {
    float t, u, v;
    uint32_t prim;
} lanes_hit;

/* Allocation of padded, aligned SoA arrays; counts are checked against
 * overflow. Return false on failure (absurd size, out of memory). */
bool lanes_rays_alloc(lanes_rays *rays, size_t count);
void lanes_rays_free(lanes_rays *rays);
bool lanes_boxes_alloc(lanes_boxes *boxes, size_t count);
void lanes_boxes_free(lanes_boxes *boxes);
bool lanes_triangles_alloc(lanes_triangles *tris, size_t count);
void lanes_triangles_free(lanes_triangles *tris);
bool lanes_tri_hits_alloc(lanes_tri_hits *hits, size_t count);
void lanes_tri_hits_free(lanes_tri_hits *hits);

/* Views of elements [first, first + count) of SoA arrays, sharing their
 * storage: a packet of a larger ray set, a BVH leaf's triangles. The
 * allocation's slack covers full-width loads from any start (see above). */
static inline lanes_rays lanes_rays_view(const lanes_rays *r, size_t first, size_t count)
{
    lanes_rays v = *r;
    v.ox += first, v.oy += first, v.oz += first;
    v.dx += first, v.dy += first, v.dz += first;
    v.rdx += first, v.rdy += first, v.rdz += first;
    v.tnear += first, v.tfar += first;
    v.count = count;
    v.capacity = r->capacity - first;
    return v;
}

static inline lanes_triangles lanes_triangles_view(const lanes_triangles *t, size_t first, size_t count)
{
    lanes_triangles v = *t;
    v.v0x += first, v.v0y += first, v.v0z += first;
    v.v1x += first, v.v1y += first, v.v1z += first;
    v.v2x += first, v.v2y += first, v.v2z += first;
    v.count = count;
    v.capacity = t->capacity - first;
    return v;
}

/* Bit-array helpers. */
static inline size_t lanes_mask_words(size_t n) { return (n + 31) / 32; }
static inline bool lanes_mask_get(const uint32_t *mask, size_t i)
{
    return (mask[i / 32] >> (i % 32)) & 1u;
}

#endif
