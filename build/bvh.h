/* Bounding volume hierarchies: a binary BVH built with the binned surface
 * area heuristic, and wide BVHs of 4, 8 or 16 children collapsed from it,
 * stored the way the kernels of that width load them.
 *
 * Compiled for the x86-64 baseline. */
#ifndef LANES_BUILD_BVH_H
#define LANES_BUILD_BVH_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "build/scene.h"
#include "trace/kernels.h"

/* Binary BVH node. Interior: count == 0, children are nodes `first` and
 * `first + 1`. Leaf: count > 0 triangles, prim_index[first .. first+count-1]. */
typedef struct lanes_bvh2_node {
    float min[3], max[3];
    uint32_t first;
    uint32_t count;
} lanes_bvh2_node;

typedef struct lanes_bvh2 {
    lanes_bvh2_node *nodes; /* nodes[0] is the root */
    size_t node_count;
    uint32_t *prim_index;   /* leaf order -> scene triangle index */
    size_t prim_count;
    /* Triangles in leaf order (triangle j is scene triangle prim_index[j]),
     * SoA, for the kernels. */
    lanes_triangles tris;
    double build_seconds;
    double sah_cost;        /* SAH cost with the costs below */
    int depth;
} lanes_bvh2;

typedef struct lanes_bvh_build_options {
    int bins;               /* SAH bins per axis (default 16) */
    int max_leaf_size;      /* default 4; leaves never exceed it unless all centroids coincide */
    float traversal_cost;   /* default 1.0 */
    float intersect_cost;   /* default 1.0 */
    int threads;            /* 0: all cores */
} lanes_bvh_build_options;

void lanes_bvh_default_options(lanes_bvh_build_options *o);

/* Builds over the scene's triangles. Degenerate triangles (NaN or infinite
 * coordinates) are left out of the tree. Returns false with a message on
 * failure (out of memory, no triangles). */
bool lanes_bvh2_build(const lanes_scene *scene, const lanes_bvh_build_options *opt,
                      lanes_bvh2 *bvh, lanes_error *err);
void lanes_bvh2_free(lanes_bvh2 *bvh);

/* Wide BVH of `width` children (4, 8 or 16). Node i's child bounds are SoA:
 * bounds + (i * 6 + p) * width holds plane p (minx, miny, minz, maxx, maxy,
 * maxz) of its `width` children, 64-byte aligned, so a kernel of that width
 * loads one plane with one aligned load. Empty child slots have
 * min = +inf, max = -inf (never hit). child[i * width + j]: for an interior
 * child, its node index; for a leaf, the first triangle (in the BVH2's leaf
 * order) with count[i * width + j] > 0 triangles; count is 0 for an interior
 * child and for an empty slot (child = LANES_WBVH_EMPTY). */
#define LANES_WBVH_EMPTY 0xffffffffu

typedef struct lanes_wbvh {
    int width;
    float *bounds;
    uint32_t *child;
    uint32_t *count;
    size_t node_count;
    double collapse_seconds;
    double sah_cost;
} lanes_wbvh;

/* Collapses by repeatedly replacing the child with the largest surface area
 * by its own children until `width` are present (SAH-guided collapse). */
bool lanes_wbvh_from_bvh2(const lanes_bvh2 *bvh, int width, lanes_wbvh *out, lanes_error *err);
void lanes_wbvh_free(lanes_wbvh *w);

/* Memory in bytes, for reports. */
size_t lanes_bvh2_bytes(const lanes_bvh2 *bvh);
size_t lanes_wbvh_bytes(const lanes_wbvh *w);

#endif
