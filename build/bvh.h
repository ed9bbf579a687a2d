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
#include "build/layout.h"

/* Every root-to-leaf path of a BVH2 built here has at most this many nodes
 * (leaf included), so traversal stacks of this size never overflow. The
 * builder switches to median splits where SAH splits could exceed it. */
#define LANES_BVH_MAX_DEPTH 64

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
    int depth;              /* nodes on the longest root-to-leaf path, leaf included */
    size_t skipped;         /* scene triangles left out (NaN or infinite coordinates) */
    /* The build options' costs, kept so the collapse and the reports use
     * the same cost model as the build. */
    float traversal_cost, intersect_cost;
    int threads;            /* threads the build ran on */
} lanes_bvh2;

typedef struct lanes_bvh_build_options {
    int bins;               /* SAH bins per axis (default 16) */
    int max_leaf_size;      /* default 4; leaves never exceed it unless all centroids coincide */
    float traversal_cost;   /* default 1.0 */
    float intersect_cost;   /* default 1.0 */
    int threads;            /* 0: all cores */
} lanes_bvh_build_options;
/* Valid options: 2 <= bins <= 256, max_leaf_size >= 1, finite costs >= 0,
 * threads >= 0. The tree is the same for every thread count. */

void lanes_bvh_default_options(lanes_bvh_build_options *o);

/* Builds over the scene's triangles. Degenerate triangles (NaN or infinite
 * coordinates) are left out of the tree. An error with a message on
 * failure (out of memory, no triangles). */
lanes_status lanes_bvh2_build(const lanes_scene *scene, const lanes_bvh_build_options *opt, lanes_bvh2 *bvh,
                              lanes_error *err);
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
    size_t node_count;      /* node 0 is the root */
    double collapse_seconds;
    double sah_cost;        /* with the BVH2's costs */
} lanes_wbvh;

/* Collapses by repeatedly replacing the child with the largest surface area
 * by its own children until `width` are present (SAH-guided collapse).
 * Leaves are BVH2 leaves, unchanged. Ties go to the earlier slot; the two
 * children of an opened node take its slot and the next, so slots keep the
 * BVH2's left-to-right order, and empty slots come last. The interior
 * children of a wide node have consecutive indices, greater than its own;
 * the root is node 0. A BVH2 whose root is a leaf gives one wide node
 * holding that leaf in slot 0. */
lanes_status lanes_wbvh_from_bvh2(const lanes_bvh2 *bvh, int width, lanes_wbvh *out, lanes_error *err);
void lanes_wbvh_free(lanes_wbvh *w);

/* Memory in bytes, for reports. The BVH2 counts its nodes, prim_index and
 * triangle arrays; the wide BVH its bounds, child and count arrays (its
 * leaves point into the BVH2's triangles). */
size_t lanes_bvh2_bytes(const lanes_bvh2 *bvh);
size_t lanes_wbvh_bytes(const lanes_wbvh *w);

/* The SAH cost model of sah_cost, for both kinds of tree:
 *   cost = sum over interior nodes n of  traversal_cost * A(n) / A(root)
 *        + sum over leaves l of  intersect_cost * count(l) * A(l) / A(root)
 * with A the surface area of the node's box. A wide node costs one
 * traversal_cost (one vector step tests all its children); its box is the
 * union of its children's; its leaves are its leaf child slots. A root of
 * zero area gives cost 0. Sums in double. */
double lanes_bvh2_sah(const lanes_bvh2 *bvh, float traversal_cost, float intersect_cost);
double lanes_wbvh_sah(const lanes_wbvh *w, float traversal_cost, float intersect_cost);

typedef struct lanes_bvh_stats {
    size_t nodes;           /* BVH2: all nodes; wide: wide nodes */
    size_t interior;        /* BVH2: interior nodes; wide: interior child slots */
    size_t leaves;          /* BVH2: leaf nodes; wide: leaf child slots */
    size_t empty_slots;     /* wide only */
    size_t prims;           /* triangles referenced by leaves */
    double avg_leaf_size;
    size_t max_leaf_size;
    double avg_children;    /* wide only: non-empty slots per node */
    int depth;              /* BVH2: nodes on the longest root-to-leaf path, leaf
                             * included; wide: wide nodes on the longest path */
    double sah_cost;        /* with the costs passed in */
    size_t bytes;           /* as lanes_*_bytes */
} lanes_bvh_stats;

/* Walks the tree from the root. Returns false (stats zeroed) when the tree
 * is empty or malformed: an index out of range, or a path longer than the
 * node count. */
bool lanes_bvh2_stats(const lanes_bvh2 *bvh, float traversal_cost, float intersect_cost,
                      lanes_bvh_stats *st);
bool lanes_wbvh_stats(const lanes_wbvh *w, float traversal_cost, float intersect_cost,
                      lanes_bvh_stats *st);

#endif
