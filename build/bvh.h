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
    int sah_block;          /* the option's: leaves cost per block of this many */
    int threads;            /* threads the build ran on */
} lanes_bvh2;

typedef struct lanes_bvh_build_options {
    int bins;               /* SAH bins per axis (default 16) */
    int max_leaf_size;      /* default 4 */
    int sah_block;          /* default 1: the SAH charges intersect_cost per block of this
                             * many triangles (ceil(n / sah_block) for a leaf of n), the
                             * cost of a kernel that tests a block at once */
    float traversal_cost;   /* default 1.0 */
    float intersect_cost;   /* default 1.0 */
    int threads;            /* 0: all cores */
} lanes_bvh_build_options;
/* Valid options: 2 <= bins <= 256, max_leaf_size >= 1, 1 <= sah_block <= 64,
 * finite costs >= 0, threads >= 0. The tree is the same for every thread count. */

void lanes_bvh_default_options(lanes_bvh_build_options *o);

/* Builds over the scene's triangles. Degenerate triangles (NaN or infinite
 * coordinates) are left out of the tree. An error with a message on
 * failure (out of memory, no triangles). */
lanes_status lanes_bvh2_build(const lanes_scene *scene, const lanes_bvh_build_options *opt, lanes_bvh2 *bvh,
                              lanes_error *err);
void lanes_bvh2_free(lanes_bvh2 *bvh);

/* Wide BVH of `width` children (4, 8 or 16), every node and every leaf one
 * contiguous block that a kernel of that width loads with aligned loads, and
 * nothing shared with the BVH2 it was collapsed from (which may be freed).
 *
 * Node i is lanes_wnode_bytes(width) bytes at nodes + i * that, 64-byte
 * aligned: float bounds[6][width] (plane p = minx, miny, minz, maxx, maxy,
 * maxz of child j at [p][j]) then uint32_t ref[width]. Empty slots have
 * min = +inf, max = -inf (never hit) and ref LANES_WBVH_EMPTY. An interior
 * child's ref is its node index; a leaf's is LANES_WREF_LEAF | first block
 * << 4 | (blocks - 1).
 *
 * Leaf block b is lanes_wblock_bytes(width) bytes at blocks + b * that:
 * float v[9][width] (v0x v0y v0z v1x v1y v1z v2x v2y v2z of triangle j at
 * [c][j]) then uint32_t prim[width], the scene triangle index. A leaf of n
 * triangles fills ceil(n / width) consecutive blocks in the BVH2's leaf
 * order; the lanes past n have prim LANES_NO_HIT and NaN vertices, and a
 * triangle of no area (its edges' cross product exactly zero, the test the
 * kernels would otherwise repeat per ray) keeps its prim but gets NaN
 * vertices: a NaN is a miss in every triangle test. Vertices are stored,
 * not edges: the watertight test needs each shared vertex exactly. */
#define LANES_WBVH_EMPTY 0xffffffffu
#define LANES_WREF_LEAF 0x80000000u
#define LANES_WBVH_MAX_BLOCKS ((1u << 27) - 1u) /* blocks a tree may hold */
#define LANES_WLEAF_MAX_BLOCKS 16u              /* blocks one leaf may span */

typedef struct lanes_wbvh {
    int width;
    unsigned char *nodes;
    size_t node_count;      /* node 0 is the root */
    unsigned char *blocks;
    size_t block_count;
    /* Set by lanes_wbvh_share: the leaf blocks hold only uint32_t
     * prim[width] (lanes_wblock_id_bytes), and the kernels gather triangle
     * prim's vertices shared_verts[3 * shared_indices[3 * prim + c] + a]
     * from these arrays, which belong to the caller. */
    const float *shared_verts;
    const uint32_t *shared_indices;
    size_t prim_count;      /* triangles in the leaves (padding lanes not counted) */
    double build_seconds;   /* lanes_wbvh_build: BVH2 and collapse; else the collapse */
    double collapse_seconds;
    double sah_cost;        /* with the BVH2's costs */
} lanes_wbvh;

static inline size_t lanes_wnode_bytes(int width) { return ((size_t)width * 28 + 63) / 64 * 64; }
static inline size_t lanes_wblock_bytes(int width) { return ((size_t)width * 40 + 31) / 32 * 32; }
static inline size_t lanes_wblock_id_bytes(int width) { return ((size_t)width * 4 + 31) / 32 * 32; }
/* The bytes from one leaf block to the next, in either layout. */
static inline size_t lanes_wblock_stride(const lanes_wbvh *w)
{
    return w->shared_verts ? lanes_wblock_id_bytes(w->width) : lanes_wblock_bytes(w->width);
}
static inline bool lanes_wref_is_leaf(uint32_t ref) { return ref != LANES_WBVH_EMPTY && (ref & LANES_WREF_LEAF); }
static inline uint32_t lanes_wref_block(uint32_t ref) { return (ref & ~LANES_WREF_LEAF) >> 4; }
static inline uint32_t lanes_wref_blocks(uint32_t ref) { return (ref & 15u) + 1u; }
static inline const float *lanes_wnode_bounds(const lanes_wbvh *w, size_t node)
{
    return (const float *)(const void *)(w->nodes + node * lanes_wnode_bytes(w->width));
}
static inline const uint32_t *lanes_wnode_refs(const lanes_wbvh *w, size_t node)
{
    return (const uint32_t *)(const void *)(lanes_wnode_bounds(w, node) + 6 * w->width);
}
/* Not for a shared tree, whose blocks hold no vertices. */
static inline const float *lanes_wblock_verts(const lanes_wbvh *w, size_t block)
{
    return (const float *)(const void *)(w->blocks + block * lanes_wblock_bytes(w->width));
}
static inline const uint32_t *lanes_wblock_prims(const lanes_wbvh *w, size_t block)
{
    const unsigned char *b = w->blocks + block * lanes_wblock_stride(w);
    return (const uint32_t *)(const void *)(w->shared_verts ? b : b + 36 * (size_t)w->width);
}

/* Collapses optimally: of all the wide trees whose nodes are cuts of the
 * BVH2 of at most `width` slots and whose leaves are the BVH2's leaves, the
 * one of least lanes_wbvh_sah cost (with the BVH2's costs, and its nodes'
 * areas, which are the wide nodes' for the tight boxes the builder makes), found by
 * dynamic programming over the BVH2 (Ylitie et al. 2017) in time
 * O(nodes * width^2) and at most nodes * (9 * width + 8) bytes of scratch.
 * Each leaf slot holds one BVH2 leaf's triangles, in blocks. Ties open the
 * node rather than keep it; slots keep the BVH2's left-to-right order, and
 * empty slots come last. The interior children of a wide node have
 * consecutive indices, greater than its own; the root is node 0. A BVH2
 * whose root is a leaf gives one wide node
 * holding that leaf in slot 0. Fails on a leaf that would span more than
 * LANES_WLEAF_MAX_BLOCKS blocks (max_leaf_size above 16 * width). */
lanes_status lanes_wbvh_from_bvh2(const lanes_bvh2 *bvh, int width, lanes_wbvh *out, lanes_error *err);
void lanes_wbvh_free(lanes_wbvh *w);

/* Turns a tree into one that shares the caller's triangles instead of
 * holding copies: its leaf blocks keep only the triangle ids (4 bytes per
 * lane instead of 40), and the kernels gather the vertices from verts and
 * indices (the arrays the tree's scene was made from: triangle i's
 * vertices at verts + 3 * indices[3 * i + c]), which must outlive the tree
 * unchanged. Triangles of no area are found per test (tris_have_area), as
 * for BVH2 leaves. The gathers take 32-bit offsets: at most
 * LANES_WBVH_SHARED_MAX triangles and vertices. Fails (the tree unchanged)
 * out of memory. */
#define LANES_WBVH_SHARED_MAX ((size_t)INT32_MAX / 3)
lanes_status lanes_wbvh_share(lanes_wbvh *w, const float *verts, const uint32_t *indices, lanes_error *err);

/* What the wide tree's SAH charges a leaf block, in units of the options'
 * intersect_cost: a block's triangle test takes about twice the vector
 * operations of a node's box test of as many lanes. Against 1, on Zen 4
 * (lanes compare, alternating runs): sponza-bunny's 8-wide tree visits 2.7
 * leaves a ray instead of 3.1 and traces primary rays 1.10-1.13x faster;
 * dragon's trees come out the same; the other rows and 16-wide trees move
 * no more than dragon's unchanged ones do between runs. */
#define LANES_WBVH_BLOCK_COST 2.0f

/* The wide BVH the kernel sets of node width `width` traverse, built for
 * it from the scene: a BVH2 whose leaves fill at most one block of `width`
 * and whose SAH charges a leaf LANES_WBVH_BLOCK_COST x intersect_cost per
 * block (one vector step for a set of that many lanes; the scalar set loops
 * over its 4-wide blocks), collapsed, then freed. base gives the other
 * options (bins, costs, threads; NULL: the defaults). build_seconds covers
 * both steps. */
lanes_status lanes_wbvh_build(const lanes_scene *scene, int width, const lanes_bvh_build_options *base,
                              lanes_wbvh *out, lanes_error *err);

/* Memory in bytes, for reports. The BVH2 counts its nodes, prim_index and
 * triangle arrays; the wide BVH its nodes and leaf blocks. */
size_t lanes_bvh2_bytes(const lanes_bvh2 *bvh);
size_t lanes_wbvh_bytes(const lanes_wbvh *w);

/* The SAH cost model of sah_cost, for both kinds of tree:
 *   cost = sum over interior nodes n of  traversal_cost * A(n) / A(root)
 *        + sum over leaves l of  intersect_cost * blocks(l) * A(l) / A(root)
 * with A the surface area of the node's box; blocks(l) is ceil(count(l) /
 * sah_block) for the BVH2 and the leaf's blocks for a wide BVH. A wide node
 * costs one traversal_cost (one vector step tests all its children); its box
 * is the union of its children's; its leaves are its leaf child slots. A root of
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
    size_t blocks;          /* wide only: leaf blocks */
    double block_fill;      /* wide only: prims / (blocks * width) */
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
