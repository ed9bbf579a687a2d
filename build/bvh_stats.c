/* Sizes, SAH costs and shape statistics of built trees, for reports and
 * tests. Everything walks the tree from the root rather than trusting the
 * node order, so it also measures trees this library did not build.
 *
 * Compiled for the x86-64 baseline. */
#include "build/bvh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static double box_area(const float lo[3], const float hi[3])
{
    double dx = (double)hi[0] - lo[0], dy = (double)hi[1] - lo[1], dz = (double)hi[2] - lo[2];
    if (!(dx >= 0.0 && dy >= 0.0 && dz >= 0.0)) return 0.0;
    return dx * dy + dy * dz + dz * dx;
}

size_t lanes_bvh2_bytes(const lanes_bvh2 *bvh)
{
    if (!bvh) return 0;
    return bvh->node_count * sizeof(lanes_bvh2_node) + bvh->prim_count * sizeof(uint32_t) +
           bvh->tris.capacity * 9 * sizeof(float);
}

size_t lanes_wbvh_bytes(const lanes_wbvh *w)
{
    if (!w) return 0;
    return w->node_count * lanes_wnode_bytes(w->width) + w->block_count * lanes_wblock_stride(w);
}

typedef struct walk_item {
    uint32_t node;
    int depth;
} walk_item;

/* A stack that grows as needed: a malformed tree may be arbitrarily deep,
 * and the walk must end with an error rather than overflow. */
typedef struct walk_stack {
    walk_item *items;
    size_t n, cap;
} walk_stack;

static bool push(walk_stack *s, uint32_t node, int depth)
{
    if (s->n == s->cap) {
        size_t c = s->cap ? 2 * s->cap : 256;
        walk_item *p = realloc(s->items, c * sizeof *p);
        if (!p) return false;
        s->items = p;
        s->cap = c;
    }
    s->items[s->n].node = node;
    s->items[s->n].depth = depth;
    s->n++;
    return true;
}

bool lanes_bvh2_stats(const lanes_bvh2 *bvh, float traversal_cost, float intersect_cost,
                      lanes_bvh_stats *st)
{
    memset(st, 0, sizeof *st);
    if (!bvh || !bvh->nodes || bvh->node_count == 0) return false;
    const lanes_bvh2_node *nd = bvh->nodes;
    const size_t nn = bvh->node_count;
    const uint32_t blk = bvh->sah_block > 0 ? (uint32_t)bvh->sah_block : 1; /* 0: a tree not built here */
    walk_stack s = {0};
    bool ok = push(&s, 0, 1);
    size_t visited = 0;
    double sum = 0.0;
    while (ok && s.n > 0) {
        walk_item it = s.items[--s.n];
        /* More visits than nodes: some node is reached twice. */
        if (++visited > nn) {
            ok = false;
            break;
        }
        const lanes_bvh2_node *n = &nd[it.node];
        double a = box_area(n->min, n->max);
        if (it.depth > st->depth) st->depth = it.depth;
        if (n->count > 0) {
            st->leaves++;
            st->prims += n->count;
            if (n->count > st->max_leaf_size) st->max_leaf_size = n->count;
            sum += (double)intersect_cost * ((n->count + blk - 1) / blk) * a;
        } else {
            st->interior++;
            sum += (double)traversal_cost * a;
            if (n->first >= nn - 1) {
                ok = false;
                break;
            }
            ok = push(&s, n->first + 1, it.depth + 1) && push(&s, n->first, it.depth + 1);
        }
    }
    free(s.items);
    if (!ok) {
        memset(st, 0, sizeof *st);
        return false;
    }
    double root = box_area(nd[0].min, nd[0].max);
    st->nodes = st->interior + st->leaves;
    st->avg_leaf_size = st->leaves ? (double)st->prims / (double)st->leaves : 0.0;
    st->sah_cost = root > 0.0 ? sum / root : 0.0;
    st->bytes = lanes_bvh2_bytes(bvh);
    return true;
}

double lanes_bvh2_sah(const lanes_bvh2 *bvh, float traversal_cost, float intersect_cost)
{
    lanes_bvh_stats st;
    if (!lanes_bvh2_stats(bvh, traversal_cost, intersect_cost, &st)) return NAN;
    return st.sah_cost;
}

bool lanes_wbvh_stats(const lanes_wbvh *w, float traversal_cost, float intersect_cost,
                      lanes_bvh_stats *st)
{
    memset(st, 0, sizeof *st);
    if (!w || !w->nodes || !w->blocks || w->node_count == 0) return false;
    if (w->width != 4 && w->width != 8 && w->width != 16) return false;
    const size_t W = (size_t)w->width, nn = w->node_count;
    walk_stack s = {0};
    bool ok = push(&s, 0, 1);
    size_t visited = 0;
    double sum = 0.0, root = 0.0;
    size_t filled = 0;
    while (ok && s.n > 0) {
        walk_item it = s.items[--s.n];
        if (++visited > nn) {
            ok = false;
            break;
        }
        st->nodes++;
        if (it.depth > st->depth) st->depth = it.depth;
        const float *b = lanes_wnode_bounds(w, it.node);
        const uint32_t *ref = lanes_wnode_refs(w, it.node);
        float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        /* Pushed in reverse so the walk visits slots in order. */
        for (size_t j = W; j-- > 0;) {
            uint32_t c = ref[j];
            if (c == LANES_WBVH_EMPTY) {
                st->empty_slots++;
                continue;
            }
            float clo[3], chi[3];
            for (int p = 0; p < 3; p++) {
                clo[p] = b[p * W + j];
                chi[p] = b[(p + 3) * W + j];
                lo[p] = clo[p] < lo[p] ? clo[p] : lo[p];
                hi[p] = chi[p] > hi[p] ? chi[p] : hi[p];
            }
            filled++;
            if (lanes_wref_is_leaf(c)) {
                uint32_t first = lanes_wref_block(c), nb = lanes_wref_blocks(c), n = 0;
                if (first > w->block_count || nb > w->block_count - first) {
                    ok = false;
                    break;
                }
                for (uint32_t blk = first; blk < first + nb; blk++) {
                    const uint32_t *prim = lanes_wblock_prims(w, blk);
                    for (size_t l = 0; l < W; l++) n += prim[l] != LANES_NO_HIT;
                }
                st->blocks += nb;
                st->leaves++;
                st->prims += n;
                if (n > st->max_leaf_size) st->max_leaf_size = n;
                sum += (double)intersect_cost * nb * box_area(clo, chi);
            } else {
                st->interior++;
                if (c >= nn) {
                    ok = false;
                    break;
                }
                ok = push(&s, c, it.depth + 1);
            }
        }
        double a = box_area(lo, hi);
        if (it.node == 0) root = a;
        sum += (double)traversal_cost * a;
    }
    free(s.items);
    if (!ok) {
        memset(st, 0, sizeof *st);
        return false;
    }
    st->avg_leaf_size = st->leaves ? (double)st->prims / (double)st->leaves : 0.0;
    st->avg_children = st->nodes ? (double)filled / (double)st->nodes : 0.0;
    st->block_fill = st->blocks ? (double)st->prims / ((double)st->blocks * (double)W) : 0.0;
    st->sah_cost = root > 0.0 ? sum / root : 0.0;
    st->bytes = lanes_wbvh_bytes(w);
    return true;
}

double lanes_wbvh_sah(const lanes_wbvh *w, float traversal_cost, float intersect_cost)
{
    lanes_bvh_stats st;
    if (!lanes_wbvh_stats(w, traversal_cost, intersect_cost, &st)) return NAN;
    return st.sah_cost;
}
