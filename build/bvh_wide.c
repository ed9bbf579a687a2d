/* Wide BVHs collapsed from the binary one: each wide node is a cut of
 * the BVH2 below one of its nodes, chosen by the optimal cost-based
 * collapse below (plan_collapse). The greedy collapse of Dammertz et al.
 * 2008 (open the child of largest area until the node is full) fills the
 * top nodes and leaves those near the leaves part empty; the optimal one
 * takes the same BVH2 and minimises the wide tree's SAH cost exactly.
 *
 * Then two passes: the first decides the slots of every node (which BVH2 node
 * each slot holds) and the leaf blocks of every leaf slot, in the order the
 * walk meets them, so that a node's leaves lie next to each other and the
 * node and block counts are known before anything is allocated; the second
 * writes nodes and blocks, on as many threads as built the BVH2, in work
 * items whose SAH sums are added in item order (the same result for every
 * thread count).
 *
 * Compiled for the x86-64 baseline. */
#define _POSIX_C_SOURCE 200809L

#include "build/bvh.h"
#include "build/bvh_alloc.h"
#include "build/parallel.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Double: float extents of huge boxes overflow, and inf * 0 would make a
 * child unopenable. */
static double node_area(const lanes_bvh2_node *n)
{
    double dx = (double)n->max[0] - n->min[0], dy = (double)n->max[1] - n->min[1],
           dz = (double)n->max[2] - n->min[2];
    if (!(dx >= 0.0 && dy >= 0.0 && dz >= 0.0)) return 0.0;
    return dx * dy + dy * dz + dz * dx;
}

void lanes_wbvh_free(lanes_wbvh *w)
{
    if (!w) return;
    free(w->nodes);
    free(w->blocks);
    memset(w, 0, sizeof *w);
}

lanes_status lanes_wbvh_share(lanes_wbvh *w, const float *verts, const uint32_t *indices, lanes_error *err)
{
    size_t stride = lanes_wblock_id_bytes(w->width);
    unsigned char *ids = lanes_big_alloc_full(w->block_count ? w->block_count : 1, stride);
    if (!ids) return lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY, "wide bvh: out of memory");
    memset(ids, 0xff, (w->block_count ? w->block_count : 1) * stride);
    for (size_t b = 0; b < w->block_count; b++)
        memcpy(ids + b * stride, lanes_wblock_prims(w, b), (size_t)w->width * sizeof(uint32_t));
    free(w->blocks);
    w->blocks = ids;
    w->shared_verts = verts;
    w->shared_indices = indices;
    return LANES_OK;
}

/* The builder's reasons are fixed texts; running out of memory is the one
 * that is not the input's fault. */
static lanes_status fail(lanes_error *err, const char *why)
{
    lanes_status status = strcmp(why, "out of memory") == 0 ? LANES_ERR_OUT_OF_MEMORY : LANES_ERR_BAD_INPUT;
    return lanes_error_set(err, status, "wide bvh: %s", why);
}

enum { FILL_BLOCK = 2048 };

typedef struct fill_ctx {
    const lanes_bvh2 *bvh;
    lanes_wbvh *out;
    const uint32_t *slot, *wchild;
    size_t count;
    double *sah;        /* per block, unnormalised */
    double root_area;   /* written by block 0 */
} fill_ctx;

/* The blocks of one leaf: triangles [first, first + count) of the BVH2's
 * leaf order, from block `block` on. */
static void fill_leaf(const lanes_bvh2 *bvh, lanes_wbvh *out, uint32_t block, uint32_t first, uint32_t count)
{
    const size_t W = (size_t)out->width;
    const lanes_triangles *t = &bvh->tris;
    const float *soa[9] = {t->v0x, t->v0y, t->v0z, t->v1x, t->v1y, t->v1z, t->v2x, t->v2y, t->v2z};
    for (uint32_t k = 0; k < count; k += (uint32_t)W, block++) {
        float *v = (float *)(void *)(out->blocks + block * lanes_wblock_bytes(out->width));
        uint32_t *prim = (uint32_t *)(void *)(v + 9 * W);
        for (size_t j = 0; j < W; j++) {
            lanes_triangle tri;
            bool real = k + j < count;
            for (int c = 0; c < 3; c++) {
                tri.v0[c] = real ? soa[c][first + k + j] : NAN;
                tri.v1[c] = real ? soa[3 + c][first + k + j] : NAN;
                tri.v2[c] = real ? soa[6 + c][first + k + j] : NAN;
            }
            bool hide = !real || lanes_triangle_no_area(&tri);
            const float *vert[3] = {tri.v0, tri.v1, tri.v2};
            for (int c = 0; c < 9; c++) v[c * W + j] = hide ? NAN : vert[c / 3][c % 3];
            prim[j] = real ? bvh->prim_index[first + k + j] : LANES_NO_HIT;
        }
    }
}

/* Pass 2 for wide nodes [item * FILL_BLOCK, ...). */
static void fill_block(void *ctx, size_t item, int tid)
{
    (void)tid;
    fill_ctx *f = ctx;
    const lanes_bvh2_node *nd = f->bvh->nodes;
    lanes_wbvh *out = f->out;
    const size_t W = (size_t)out->width;
    const double ct = f->bvh->traversal_cost, ci = f->bvh->intersect_cost;
    size_t begin = item * FILL_BLOCK, end = begin + FILL_BLOCK < f->count ? begin + FILL_BLOCK : f->count;
    double sah = 0.0;
    for (size_t i = begin; i < end; i++) {
        float *b = (float *)(void *)(out->nodes + i * lanes_wnode_bytes(out->width));
        memset(b, 0, lanes_wnode_bytes(out->width)); /* the padding too: trees compare bytewise */
        uint32_t *ref = (uint32_t *)(void *)(b + 6 * W);
        float box[6] = {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY};
        for (size_t j = 0; j < W; j++) {
            size_t k = i * W + j;
            uint32_t s = f->slot[k];
            if (s == UINT32_MAX) {
                for (int p = 0; p < 3; p++) {
                    b[p * W + j] = INFINITY;
                    b[(p + 3) * W + j] = -INFINITY;
                }
                ref[j] = LANES_WBVH_EMPTY;
                continue;
            }
            const lanes_bvh2_node *c = &nd[s];
            for (int p = 0; p < 3; p++) {
                b[p * W + j] = c->min[p];
                b[(p + 3) * W + j] = c->max[p];
                box[p] = c->min[p] < box[p] ? c->min[p] : box[p];
                box[p + 3] = c->max[p] > box[p + 3] ? c->max[p] : box[p + 3];
            }
            ref[j] = f->wchild[k];
            if (c->count > 0) {
                fill_leaf(f->bvh, out, lanes_wref_block(ref[j]), c->first, c->count);
                sah += ci * lanes_wref_blocks(ref[j]) * node_area(c);
            }
        }
        lanes_bvh2_node u;
        memcpy(u.min, box, sizeof u.min);
        memcpy(u.max, box + 3, sizeof u.max);
        double a = node_area(&u);
        sah += ct * a;
        if (i == 0) f->root_area = a;
    }
    f->sah[item] = sah;
}

/* The optimal collapse (the dynamic programme of Ylitie, Karras and Laine
 * 2017, without their leaf merging: the wide tree keeps the BVH2's leaves,
 * whose sizes the BVH2's SAH already chose per block). For a BVH2 node n
 * and i = 1 .. width, cost(n, i) is the least SAH cost (unnormalised, as
 * lanes_wbvh_sah counts it) of the subtree under n when it may take up to i
 * slots of its parent wide node:
 *   a leaf:     intersect_cost * blocks * A(n), for every i;
 *   interior:   split(n, j) = min over k of cost(left, k) + cost(right, j - k),
 *               cost(n, 1)  = traversal_cost * A(n) + split(n, width)
 *                             (n becomes a wide node of its own),
 *               cost(n, i)  = min(cost(n, 1), split(n, i)) for i >= 2.
 * The root is a wide node: split(root, width). Greedy opening by surface
 * area spends a wide node's slots on its largest children and leaves the
 * nodes below part empty; this spends them where they save the most. Ties open the node (fewer, fuller wide nodes), and
 * the first k wins. */
typedef struct collapse_plan {
    const lanes_bvh2_node *nodes;
    size_t width;
    double *cost;    /* cost(n, i) at [n * width + i - 1] */
    uint8_t *split;  /* [n * width]: the k of split(n, width), n's own node;
                      * [n * width + i - 1], i >= 2: 0 when cost(n, i) is
                      * cost(n, 1), else the k of split(n, i) */
} collapse_plan;

static void plan_free(collapse_plan *p)
{
    free(p->cost);
    free(p->split);
    p->cost = NULL;
    p->split = NULL;
}

static bool plan_collapse(const lanes_bvh2 *bvh, size_t W, collapse_plan *p, const char **why)
{
    const lanes_bvh2_node *nd = bvh->nodes;
    const size_t nn = bvh->node_count;
    const double ct = bvh->traversal_cost, ci = bvh->intersect_cost;
    p->nodes = nd;
    p->width = W;
    p->cost = lanes_big_alloc_full(nn * W, sizeof *p->cost);
    p->split = lanes_big_alloc_full(nn * W, sizeof *p->split);
    uint32_t *order = lanes_big_alloc_full(nn, sizeof *order);
    uint32_t *stack = lanes_big_alloc(nn + 1, sizeof *stack);
    bool ok = p->cost && p->split && order && stack;
    *why = "out of memory";
    size_t n_order = 0, sp = 0;
    if (ok) stack[sp++] = 0;
    while (ok && sp > 0) {
        uint32_t n = stack[--sp];
        if (n_order == nn) {
            ok = false;
            *why = "malformed BVH2: a node reached twice";
            break;
        }
        order[n_order++] = n;
        if (nd[n].count > 0) continue;
        if (nd[n].first >= nn - 1) {
            ok = false;
            *why = "malformed BVH2: child index out of range";
            break;
        }
        stack[sp++] = nd[n].first + 1;
        stack[sp++] = nd[n].first;
    }
    for (size_t o = n_order; ok && o-- > 0;) {
        const size_t n = order[o];
        double *c = p->cost + n * W;
        uint8_t *sk = p->split + n * W;
        if (nd[n].count > 0) {
            double leaf = ci * (double)((nd[n].count + W - 1) / W) * node_area(&nd[n]);
            for (size_t i = 0; i < W; i++) c[i] = leaf, sk[i] = 0;
            continue;
        }
        const double *cl = p->cost + (size_t)nd[n].first * W, *cr = cl + W;
        double split[17];
        uint8_t best_k[17];
        for (size_t j = 2; j <= W; j++) {
            split[j] = INFINITY;
            best_k[j] = 1;
            for (size_t k = 1; k < j; k++) {
                double v = cl[k - 1] + cr[j - k - 1];
                if (v < split[j]) split[j] = v, best_k[j] = (uint8_t)k;
            }
        }
        c[0] = ct * node_area(&nd[n]) + split[W];
        sk[0] = best_k[W];
        for (size_t i = 2; i <= W; i++) {
            bool open = split[i] <= c[0];
            c[i - 1] = open ? split[i] : c[0];
            sk[i - 1] = open ? best_k[i] : 0;
        }
    }
    free(order);
    free(stack);
    /* Only the splits are read from here on: the costs are the bulk of the
     * scratch (8 * width bytes per BVH2 node). */
    free(p->cost);
    p->cost = NULL;
    if (!ok) plan_free(p);
    return ok;
}

/* Appends the slots the plan gives BVH2 node n when it may take up to i. */
static void plan_slots(const collapse_plan *p, uint32_t n, int i, uint32_t *s, int *m)
{
    const lanes_bvh2_node *nd = &p->nodes[n];
    int k = i >= 2 && nd->count == 0 ? p->split[(size_t)n * p->width + (size_t)i - 1] : 0;
    if (k == 0) {
        s[(*m)++] = n;
        return;
    }
    plan_slots(p, nd->first, k, s, m);
    plan_slots(p, nd->first + 1, i - k, s, m);
}

lanes_status lanes_wbvh_from_bvh2(const lanes_bvh2 *bvh, int width, lanes_wbvh *out, lanes_error *err)
{
    double t0 = now_seconds();
    if (!out) return fail(err, "no output");
    memset(out, 0, sizeof *out);
    if (width != 4 && width != 8 && width != 16) return fail(err, "width must be 4, 8 or 16");
    if (!bvh || !bvh->nodes || bvh->node_count == 0) return fail(err, "empty BVH2");
    const lanes_bvh2_node *nd = bvh->nodes;
    const size_t nn = bvh->node_count;
    const size_t W = (size_t)width;

    /* Pass 0: the optimal cut of every subtree, children before parents
     * (reverse preorder). */
    collapse_plan plan;
    const char *why = "out of memory";
    bool ok = plan_collapse(bvh, W, &plan, &why);

    /* Pass 1. roots[i]: the BVH2 node wide node i stands for; slot[i*W+j]:
     * the BVH2 node in slot j (UINT32_MAX: empty); wchild: the wide index
     * of interior slots. Every wide node but the root stands for a distinct
     * interior BVH2 node, and a well-formed BVH2 of nn nodes has
     * (nn - 1) / 2 of them (two children each), which bounds the count.
     * A node's interior children get consecutive indices when it is
     * processed, and nodes are processed depth first from a stack: that
     * follows the BVH2's depth-first layout, where breadth first order
     * would jump around the BVH2 node array. */
    const size_t cap = (nn - 1) / 2 + 1;
    uint32_t *roots = lanes_big_alloc(cap, sizeof *roots);
    uint32_t *stack = lanes_big_alloc(cap, sizeof *stack);
    uint32_t *slot = lanes_big_alloc(cap * W, sizeof *slot);
    uint32_t *wchild = lanes_big_alloc(cap * W, sizeof *wchild);
    ok = ok && roots && stack && slot && wchild;
    size_t count = 1, sp = 0, blocks = 0;
    if (ok) {
        roots[0] = 0;
        stack[sp++] = 0;
    }
    while (ok && sp > 0) {
        size_t i = stack[--sp];
        size_t first_new = count;
        uint32_t s[16];
        int m = 0;
        const lanes_bvh2_node *r = &nd[roots[i]];
        if (r->count > 0) {
            s[m++] = roots[i];
        } else {
            int k = plan.split[(size_t)roots[i] * W];
            plan_slots(&plan, r->first, k, s, &m);
            plan_slots(&plan, r->first + 1, width - k, s, &m);
        }
        for (int j = 0; ok && j < width; j++) {
            size_t k = i * W + (size_t)j;
            if (j >= m) {
                slot[k] = UINT32_MAX;
                wchild[k] = LANES_WBVH_EMPTY;
                continue;
            }
            slot[k] = s[j];
            const lanes_bvh2_node *c = &nd[s[j]];
            if (c->count > 0) {
                size_t nb = (c->count + W - 1) / W;
                if (c->first > bvh->prim_count || c->count > bvh->prim_count - c->first) {
                    ok = false;
                    why = "malformed BVH2: leaf range out of range";
                } else if (nb > LANES_WLEAF_MAX_BLOCKS) {
                    ok = false;
                    why = "a leaf spans more than 16 blocks (max_leaf_size above 16 * width)";
                } else if (blocks + nb > LANES_WBVH_MAX_BLOCKS) {
                    ok = false;
                    why = "too many triangles for one tree";
                } else {
                    wchild[k] = LANES_WREF_LEAF | (uint32_t)blocks << 4 | (uint32_t)(nb - 1);
                    blocks += nb;
                }
                continue;
            }
            if (count == cap || count >= LANES_WREF_LEAF) {
                ok = false;
                why = "malformed BVH2: more interior nodes than (nodes - 1) / 2";
                break;
            }
            wchild[k] = (uint32_t)count;
            roots[count++] = s[j];
        }
        for (size_t c = count; ok && c-- > first_new;) stack[sp++] = (uint32_t)c;
    }

    /* Pass 2. */
    if (ok) {
        out->width = width;
        out->node_count = count;
        out->block_count = blocks;
        out->prim_count = bvh->prim_count;
        out->nodes = lanes_big_alloc_full(count, lanes_wnode_bytes(width));
        out->blocks = lanes_big_alloc_full(blocks ? blocks : 1, lanes_wblock_bytes(width));
        ok = out->nodes && out->blocks;
    }
    double sah = 0.0, root_area = 0.0;
    if (ok) {
        fill_ctx f = {bvh, out, slot, wchild, count, NULL, 0.0};
        size_t blocks = (count + FILL_BLOCK - 1) / FILL_BLOCK;
        f.sah = malloc(blocks * sizeof *f.sah);
        ok = f.sah != NULL;
        if (ok) {
            lanes_pool p;
            lanes_pool_start(&p, blocks > 1 && bvh->threads > 1 ? bvh->threads : 1, NULL, 0);
            lanes_pool_run(&p, blocks, fill_block, &f);
            lanes_pool_stop(&p);
            for (size_t i = 0; i < blocks; i++) sah += f.sah[i];
            root_area = f.root_area;
        }
        free(f.sah);
    }
    free(roots);
    free(stack);
    free(slot);
    free(wchild);
    plan_free(&plan);
    if (!ok) {
        lanes_wbvh_free(out);
        return fail(err, why);
    }
    out->sah_cost = root_area > 0.0 ? sah / root_area : 0.0;
    out->collapse_seconds = now_seconds() - t0;
    out->build_seconds = out->collapse_seconds;
    return LANES_OK;
}

lanes_status lanes_wbvh_build(const lanes_scene *scene, int width, const lanes_bvh_build_options *base,
                              lanes_wbvh *out, lanes_error *err)
{
    if (!out) return fail(err, "no output");
    memset(out, 0, sizeof *out);
    if (width != 4 && width != 8 && width != 16) return fail(err, "width must be 4, 8 or 16");
    lanes_bvh_build_options o;
    if (base) o = *base;
    else lanes_bvh_default_options(&o);
    o.max_leaf_size = width;
    o.sah_block = width;
    o.intersect_cost *= LANES_WBVH_BLOCK_COST;
    lanes_bvh2 bvh;
    lanes_status status = lanes_bvh2_build(scene, &o, &bvh, err);
    if (status != LANES_OK) return status;
    status = lanes_wbvh_from_bvh2(&bvh, width, out, err);
    if (status == LANES_OK) out->build_seconds = bvh.build_seconds + out->collapse_seconds;
    lanes_bvh2_free(&bvh);
    return status;
}
