/* Tests of the BVH2 builder, the wide collapse and the statistics.
 *
 *   test_bvh            generated scenes (random, grid, sphere, degenerate)
 *   test_bvh --meshes   the .off meshes in $LANES_MESH_DIR (or out/meshes);
 *                       exit status 77 (skipped) when there are none
 *
 * Every property is checked against values this file computes itself from
 * the scene's floats: triangle bounds, coverage, the SAH sum, and for wide
 * trees the correspondence to the BVH2 they came from. The checkers are run
 * on deliberately corrupted trees too, so a checker that accepts anything
 * fails the test. */
#define _POSIX_C_SOURCE 200809L

#include <dirent.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "build/bvh.h"
#include "tests/harness.h"

#define LANES_PI 3.14159265358979323846

static bool g_quiet; /* inside the negative tests: failures are expected */
static char g_context[256];

static bool failf(int line, const char *fmt, ...)
{
    if (g_quiet) return false;
    va_list ap;
    va_start(ap, fmt);
    fprintf(stderr, "FAIL [%s] test_bvh.c:%d: ", g_context, line);
    vfprintf(stderr, fmt, ap);
    fprintf(stderr, "\n");
    va_end(ap);
    return false;
}
/* The validators' own test: a tree that breaks a rule makes the validator
 * return false with the reason (the negative tests expect exactly that);
 * the tests' checks are the harness's CHECK. */
#define REQUIRE(cond, ...)                                        \
    do {                                                          \
        if (!(cond)) return failf(__LINE__, __VA_ARGS__);         \
    } while (0)

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ---------------------------------------------------------------- scenes */

static uint64_t g_rng;
static uint64_t rng_next(void)
{
    uint64_t z = (g_rng += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}
static float rng_float(void) { return (float)(rng_next() >> 40) * (1.0f / 16777216.0f); }

static lanes_scene make_scene(const char *name, size_t n)
{
    lanes_scene s;
    memset(&s, 0, sizeof s);
    snprintf(s.name, sizeof s.name, "%s", name);
    s.triangle_count = n;
    s.verts = calloc(n ? 9 * n : 1, sizeof(float));
    if (!s.verts) {
        fprintf(stderr, "out of memory\n");
        exit(1);
    }
    return s;
}

static void free_scene(lanes_scene *s)
{
    free(s->verts);
    s->verts = NULL;
}

/* Triangles of widely varying size scattered in a box. */
static lanes_scene gen_random(size_t n, uint64_t seed)
{
    lanes_scene s = make_scene("random", n);
    g_rng = seed;
    for (size_t i = 0; i < n; i++) {
        float c[3], size = 0.01f + 2.0f * rng_float() * rng_float() * rng_float();
        for (int a = 0; a < 3; a++) c[a] = 20.0f * rng_float() - 10.0f;
        for (int k = 0; k < 9; k++) s.verts[9 * i + k] = c[k % 3] + size * (rng_float() - 0.5f);
    }
    return s;
}

/* A flat grid in z = 0: every box has zero extent in z. */
static lanes_scene gen_grid(int nx, int ny)
{
    lanes_scene s = make_scene("grid", (size_t)2 * nx * ny);
    size_t t = 0;
    for (int y = 0; y < ny; y++)
        for (int x = 0; x < nx; x++) {
            float q[4][3] = {{(float)x, (float)y, 0}, {(float)x + 1, (float)y, 0},
                             {(float)x, (float)y + 1, 0}, {(float)x + 1, (float)y + 1, 0}};
            int tri[2][3] = {{0, 1, 2}, {1, 3, 2}};
            for (int k = 0; k < 2; k++, t++)
                for (int m = 0; m < 3; m++) memcpy(s.verts + 9 * t + 3 * m, q[tri[k][m]], 12);
        }
    return s;
}

static lanes_scene gen_sphere(int stacks, int slices)
{
    lanes_scene s = make_scene("sphere", (size_t)2 * stacks * slices);
    size_t t = 0;
    for (int i = 0; i < stacks; i++)
        for (int j = 0; j < slices; j++) {
            float p[4][3];
            for (int k = 0; k < 4; k++) {
                double th = LANES_PI * (i + (k >> 1)) / stacks, ph = 2 * LANES_PI * (j + (k & 1)) / slices;
                p[k][0] = (float)(sin(th) * cos(ph));
                p[k][1] = (float)cos(th);
                p[k][2] = (float)(sin(th) * sin(ph));
            }
            int tri[2][3] = {{0, 2, 1}, {1, 2, 3}};
            for (int k = 0; k < 2; k++, t++)
                for (int m = 0; m < 3; m++) memcpy(s.verts + 9 * t + 3 * m, p[tri[k][m]], 12);
        }
    return s;
}

static lanes_scene gen_same(size_t n)
{
    lanes_scene s = make_scene("same", n);
    const float tri[9] = {0.25f, 0.5f, 1.0f, 2.0f, 0.5f, 1.0f, 0.25f, 3.0f, -1.0f};
    for (size_t i = 0; i < n; i++) memcpy(s.verts + 9 * i, tri, sizeof tri);
    return s;
}

/* Random triangles with a NaN or an infinity in every fifth (and a few
 * more); returns how many were spoiled. */
static lanes_scene gen_nan_mixed(size_t n, size_t *spoiled)
{
    lanes_scene s = gen_random(n, 77);
    snprintf(s.name, sizeof s.name, "nan-mixed");
    const float bad[3] = {NAN, INFINITY, -INFINITY};
    *spoiled = 0;
    for (size_t i = 0; i < n; i++)
        if (i % 5 == 0 || i == n - 1) {
            s.verts[9 * i + rng_next() % 9] = bad[rng_next() % 3];
            (*spoiled)++;
        }
    return s;
}

/* Centroids spaced geometrically down to zero: equal-width bins peel off
 * a few at a time, so SAH alone would go far deeper than 64 levels. */
static lanes_scene gen_geometric(size_t n)
{
    lanes_scene s = make_scene("geometric", n);
    for (size_t i = 0; i < n; i++) {
        float x = ldexpf(1.0f, -(int)(i % 140)) * (1.0f + (float)(i / 140) * 1e-3f);
        const float tri[9] = {x, 0, 0, x * 1.0001f, 1, 0, x, 0, 1};
        memcpy(s.verts + 9 * i, tri, sizeof tri);
    }
    return s;
}

/* Coordinates near the float limits, and tiny (subnormal) triangles. */
static lanes_scene gen_extreme(void)
{
    lanes_scene s = make_scene("extreme", 64);
    g_rng = 5;
    for (size_t i = 0; i < 64; i++) {
        float scale = i % 2 ? 3e38f : 1e-40f;
        for (int k = 0; k < 9; k++) s.verts[9 * i + k] = scale * (2.0f * rng_float() - 1.0f);
    }
    return s;
}

/* ------------------------------------------------------- BVH2 checking */

static bool tri_finite(const float *t)
{
    for (int k = 0; k < 9; k++)
        if (!isfinite(t[k])) return false;
    return true;
}

static void tri_box(const float *t, float lo[3], float hi[3])
{
    for (int a = 0; a < 3; a++) {
        lo[a] = fminf(fminf(t[a], t[3 + a]), t[6 + a]);
        hi[a] = fmaxf(fmaxf(t[a], t[3 + a]), t[6 + a]);
    }
}

static double area(const float lo[3], const float hi[3])
{
    double dx = (double)hi[0] - lo[0], dy = (double)hi[1] - lo[1], dz = (double)hi[2] - lo[2];
    if (!(dx >= 0.0 && dy >= 0.0 && dz >= 0.0)) return 0.0;
    return dx * dy + dy * dz + dz * dx;
}

static bool same_box(const float alo[3], const float ahi[3], const float blo[3], const float bhi[3])
{
    for (int a = 0; a < 3; a++)
        if (alo[a] != blo[a] || ahi[a] != bhi[a]) return false;
    return true;
}

/* What the checker learns about a BVH2, reused by the wide checks. */
typedef struct bvh2_info {
    uint32_t *lo, *hi;   /* range of leaf positions under each node */
    size_t leaves, interior;
    int depth;
    double sah;          /* unnormalised */
} bvh2_info;

static void info_free(bvh2_info *in)
{
    free(in->lo);
    free(in->hi);
    memset(in, 0, sizeof *in);
}

typedef struct check2 {
    const lanes_scene *sc;
    const lanes_bvh2 *b;
    int maxleaf;
    float ct, ci;
    uint8_t *visited;
    uint8_t *cover;
    bvh2_info *in;
} check2;

/* Returns the exact bounds of node's triangles through lo/hi. */
static bool check_node(check2 *c, uint32_t node, int depth, float lo[3], float hi[3])
{
    const lanes_bvh2 *b = c->b;
    REQUIRE(node < b->node_count, "node index %u out of range", node);
    REQUIRE(!c->visited[node], "node %u reached twice", node);
    REQUIRE(depth <= LANES_BVH_MAX_DEPTH, "path longer than %d", LANES_BVH_MAX_DEPTH);
    c->visited[node] = 1;
    if (depth > c->in->depth) c->in->depth = depth;
    const lanes_bvh2_node *n = &b->nodes[node];
    double a = area(n->min, n->max);
    if (n->count > 0) {
        REQUIRE(n->first <= b->prim_count && n->count <= b->prim_count - n->first,
              "leaf %u range out of bounds", node);
        for (int k = 0; k < 3; k++) lo[k] = INFINITY, hi[k] = -INFINITY;
        bool same_centroid = true;
        float c0[3] = {0, 0, 0};
        for (uint32_t j = n->first; j < n->first + n->count; j++) {
            REQUIRE(!c->cover[j], "triangle position %u in two leaves", j);
            c->cover[j] = 1;
            uint32_t id = b->prim_index[j];
            REQUIRE(id < c->sc->triangle_count, "prim_index[%u] out of range", j);
            const float *t = c->sc->verts + 9 * (size_t)id;
            REQUIRE(tri_finite(t), "skipped triangle %u is in the tree", id);
            const lanes_triangles *tr = &b->tris;
            const float soa[9] = {tr->v0x[j], tr->v0y[j], tr->v0z[j], tr->v1x[j], tr->v1y[j],
                                  tr->v1z[j], tr->v2x[j], tr->v2y[j], tr->v2z[j]};
            REQUIRE(!memcmp(soa, t, sizeof soa), "tris[%u] is not scene triangle %u", j, id);
            float tl[3], th[3];
            tri_box(t, tl, th);
            for (int k = 0; k < 3; k++) {
                lo[k] = fminf(lo[k], tl[k]);
                hi[k] = fmaxf(hi[k], th[k]);
                float cc = tl[k] + th[k];
                if (j == n->first) c0[k] = cc;
                else if (cc != c0[k]) same_centroid = false;
            }
        }
        REQUIRE((int)n->count <= c->maxleaf || same_centroid,
              "leaf %u holds %u > %d triangles whose centroids differ", node, n->count, c->maxleaf);
        REQUIRE(same_box(n->min, n->max, lo, hi), "leaf %u bounds are not its triangles' bounds",
              node);
        c->in->lo[node] = n->first;
        c->in->hi[node] = n->first + n->count;
        c->in->leaves++;
        uint32_t blk = (uint32_t)b->sah_block;
        c->in->sah += (double)c->ci * ((n->count + blk - 1) / blk) * a;
        return true;
    }
    REQUIRE(n->first + 1 < b->node_count,
          "interior %u has children %u, %u out of range", node, n->first, n->first + 1);
    float llo[3], lhi[3], rlo[3], rhi[3];
    if (!check_node(c, n->first, depth + 1, llo, lhi)) return false;
    if (!check_node(c, n->first + 1, depth + 1, rlo, rhi)) return false;
    const lanes_bvh2_node *l = &b->nodes[n->first], *r = &b->nodes[n->first + 1];
    for (int k = 0; k < 3; k++) {
        REQUIRE(l->min[k] >= n->min[k] && l->max[k] <= n->max[k] && r->min[k] >= n->min[k] &&
                  r->max[k] <= n->max[k],
              "children of %u not inside it", node);
        lo[k] = fminf(llo[k], rlo[k]);
        hi[k] = fmaxf(lhi[k], rhi[k]);
    }
    REQUIRE(same_box(n->min, n->max, lo, hi), "node %u bounds are not the union of its contents",
          node);
    /* Children's ranges are adjacent: every subtree is one contiguous run. */
    REQUIRE(c->in->hi[n->first] == c->in->lo[n->first + 1], "children of %u not contiguous", node);
    c->in->lo[node] = c->in->lo[n->first];
    c->in->hi[node] = c->in->hi[n->first + 1];
    c->in->interior++;
    c->in->sah += (double)c->ct * a;
    return true;
}

static bool close_rel(double a, double b, double tol)
{
    return fabs(a - b) <= tol * fmax(fabs(a), fabs(b)) || (a == 0.0 && b == 0.0);
}

static bool check_bvh2(const lanes_scene *sc, const lanes_bvh2 *b, const lanes_bvh_build_options *o,
                       bvh2_info *in)
{
    size_t kept = 0;
    for (size_t i = 0; i < sc->triangle_count; i++) kept += tri_finite(sc->verts + 9 * i);
    REQUIRE(b->prim_count == kept, "prim_count %zu, expected %zu", b->prim_count, kept);
    REQUIRE(b->skipped == sc->triangle_count - kept, "skipped %zu, expected %zu", b->skipped,
          sc->triangle_count - kept);
    REQUIRE(b->node_count >= 1 && b->node_count <= 2 * kept - 1, "node_count %zu", b->node_count);
    REQUIRE(b->tris.count == kept && b->tris.capacity >= kept, "tris count %zu", b->tris.count);
    memset(in, 0, sizeof *in);
    in->lo = calloc(b->node_count, sizeof *in->lo);
    in->hi = calloc(b->node_count, sizeof *in->hi);
    check2 c = {sc, b, o->max_leaf_size, o->traversal_cost, o->intersect_cost,
                calloc(b->node_count, 1), calloc(kept, 1), in};
    bool ok = in->lo && in->hi && c.visited && c.cover;
    float lo[3], hi[3];
    ok = ok && check_node(&c, 0, 1, lo, hi);
    for (size_t i = 0; ok && i < b->node_count; i++)
        if (!c.visited[i]) ok = failf(__LINE__, "node %zu unreachable", i);
    for (size_t j = 0; ok && j < kept; j++)
        if (!c.cover[j]) ok = failf(__LINE__, "triangle position %zu in no leaf", j);
    /* prim_index is a permutation of the kept triangles (coverage above
     * plus distinctness here). */
    uint8_t *seen = calloc(sc->triangle_count, 1);
    for (size_t j = 0; ok && j < kept; j++) {
        uint32_t id = b->prim_index[j];
        if (seen[id]) ok = failf(__LINE__, "scene triangle %u appears twice", id);
        seen[id] = 1;
    }
    free(seen);
    free(c.visited);
    free(c.cover);
    if (!ok) return false;
    REQUIRE(in->depth == b->depth, "depth %d, walked %d", b->depth, in->depth);
    double root = area(b->nodes[0].min, b->nodes[0].max);
    double sah = root > 0 ? in->sah / root : 0.0;
    REQUIRE(isfinite(sah) && isfinite(b->sah_cost), "SAH not finite");
    REQUIRE(close_rel(sah, b->sah_cost, 1e-9), "SAH %.17g, recomputed %.17g", b->sah_cost, sah);
    double s2 = lanes_bvh2_sah(b, o->traversal_cost, o->intersect_cost);
    REQUIRE(close_rel(sah, s2, 1e-9), "lanes_bvh2_sah %.17g, recomputed %.17g", s2, sah);
    lanes_bvh_stats st;
    REQUIRE(lanes_bvh2_stats(b, o->traversal_cost, o->intersect_cost, &st), "stats failed");
    REQUIRE(st.nodes == b->node_count && st.leaves == in->leaves && st.interior == in->interior &&
              st.prims == kept && st.depth == in->depth,
          "stats disagree: nodes %zu leaves %zu prims %zu depth %d", st.nodes, st.leaves,
          st.prims, st.depth);
    REQUIRE(st.bytes == lanes_bvh2_bytes(b) && st.bytes >= b->node_count * 32, "bytes");
    return true;
}

/* ------------------------------------------------------- wide checking */

typedef struct checkw {
    const lanes_bvh2 *b;
    const lanes_wbvh *w;
    const bvh2_info *in;
    uint32_t *wlo, *whi;    /* triangle range under each wide node */
    uint32_t *slo, *shi;    /* and under each slot */
    uint32_t *pos_of;       /* scene triangle -> position in the BVH2's leaf order */
    uint8_t *visited;
    uint8_t *cover;
    uint8_t *block_seen;
    int depth;
    double sah;
} checkw;

static const float *plane(const lanes_wbvh *w, size_t node, int p)
{
    return lanes_wnode_bounds(w, node) + (size_t)p * (size_t)w->width;
}

static uint32_t slot_ref(const lanes_wbvh *w, size_t node, int j) { return lanes_wnode_refs(w, node)[j]; }

static void slot_box(const lanes_wbvh *w, size_t node, int j, float lo[3], float hi[3])
{
    for (int p = 0; p < 3; p++) {
        lo[p] = plane(w, node, p)[j];
        hi[p] = plane(w, node, p + 3)[j];
    }
}

static bool slot_empty(const lanes_wbvh *w, size_t node, int j) { return slot_ref(w, node, j) == LANES_WBVH_EMPTY; }

/* The float test the kernels would make per ray: a triangle whose edges'
 * cross product is exactly zero is never hit, and its block lane holds NaN. */
static bool zero_area(const float v[9])
{
    float e1[3], e2[3];
    for (int a = 0; a < 3; a++) e1[a] = v[3 + a] - v[a], e2[a] = v[6 + a] - v[a];
    return e1[1] * e2[2] - e1[2] * e2[1] == 0.0f && e1[2] * e2[0] - e1[0] * e2[2] == 0.0f &&
           e1[0] * e2[1] - e1[1] * e2[0] == 0.0f;
}

/* A leaf slot's blocks: reached once, holding consecutive triangles of the
 * BVH2's leaf order, each a bit-exact copy (or NaN where it has no area),
 * padding only after the last triangle, as few blocks as the count needs.
 * Sets the slot's range of leaf positions. */
static bool check_leaf(checkw *c, uint32_t ref, uint32_t *lo, uint32_t *hi)
{
    const lanes_wbvh *w = c->w;
    const lanes_triangles *t = &c->b->tris;
    const float *soa[9] = {t->v0x, t->v0y, t->v0z, t->v1x, t->v1y, t->v1z, t->v2x, t->v2y, t->v2z};
    const size_t W = (size_t)w->width;
    uint32_t first = lanes_wref_block(ref), nb = lanes_wref_blocks(ref), n = 0;
    REQUIRE(first < w->block_count && nb <= w->block_count - first, "leaf blocks out of range");
    bool ended = false;
    for (uint32_t blk = first; blk < first + nb; blk++) {
        REQUIRE(!c->block_seen[blk], "block %u reached twice", blk);
        c->block_seen[blk] = 1;
        const float *v = lanes_wblock_verts(w, blk);
        const uint32_t *prim = lanes_wblock_prims(w, blk);
        for (size_t j = 0; j < W; j++) {
            if (prim[j] == LANES_NO_HIT) {
                ended = true;
                for (int f = 0; f < 9; f++) REQUIRE(isnan(v[f * W + j]), "padding lane %zu of block %u not NaN", j, blk);
                continue;
            }
            REQUIRE(!ended, "block %u: a triangle after padding", blk);
            REQUIRE(prim[j] < c->b->prim_count + c->b->skipped, "block %u lane %zu: prim %u out of range", blk, j, prim[j]);
            uint32_t pos = c->pos_of[prim[j]];
            REQUIRE(pos != UINT32_MAX, "block %u: prim %u is in no BVH2 leaf", blk, prim[j]);
            if (n == 0) *lo = pos;
            REQUIRE(pos == *lo + n, "leaf at block %u: triangles not consecutive in leaf order", first);
            float tv[9];
            for (int f = 0; f < 9; f++) tv[f] = soa[f][pos];
            bool flat = zero_area(tv);
            for (int f = 0; f < 9; f++)
                REQUIRE(flat ? isnan(v[f * W + j]) : !memcmp(&v[f * W + j], &tv[f], sizeof(float)),
                        "block %u lane %zu: vertex data differ from the BVH2's", blk, j);
            n++;
        }
    }
    REQUIRE(n > 0 && (n + W - 1) / W == nb, "leaf of %u triangles in %u blocks", n, nb);
    *hi = *lo + n;
    return true;
}

/* Pass 1: ranges, coverage, layout of every node, reachability, SAH. */
static bool walk_wide(checkw *c, uint32_t node, int depth)
{
    const lanes_wbvh *w = c->w;
    const int W = w->width;
    REQUIRE(node < w->node_count, "wide node %u out of range", node);
    REQUIRE(!c->visited[node], "wide node %u reached twice", node);
    REQUIRE(depth <= LANES_BVH_MAX_DEPTH, "wide path too long");
    c->visited[node] = 1;
    if (depth > c->depth) c->depth = depth;
    uint32_t lo = UINT32_MAX, hi = 0, total = 0;
    float blo[3] = {INFINITY, INFINITY, INFINITY}, bhi[3] = {-INFINITY, -INFINITY, -INFINITY};
    bool seen_empty = false;
    int filled = 0;
    for (int j = 0; j < W; j++) {
        size_t k = (size_t)node * W + j;
        float slo[3], shi[3];
        slot_box(w, node, j, slo, shi);
        if (slot_empty(w, node, j)) {
            for (int p = 0; p < 3; p++)
                REQUIRE(slo[p] == INFINITY && shi[p] == -INFINITY,
                      "empty slot %d of wide node %u has bounds", j, node);
            seen_empty = true;
            continue;
        }
        REQUIRE(!seen_empty, "wide node %u: filled slot %d after an empty one", node, j);
        filled++;
        for (int p = 0; p < 3; p++) {
            REQUIRE(slo[p] <= shi[p], "slot %d of wide node %u has an empty box", j, node);
            blo[p] = fminf(blo[p], slo[p]);
            bhi[p] = fmaxf(bhi[p], shi[p]);
        }
        uint32_t ref = slot_ref(w, node, j);
        if (lanes_wref_is_leaf(ref)) {
            if (!check_leaf(c, ref, &c->slo[k], &c->shi[k])) return false;
            for (uint32_t t = c->slo[k]; t < c->shi[k]; t++) {
                REQUIRE(!c->cover[t], "triangle position %u reached twice in the wide BVH", t);
                c->cover[t] = 1;
            }
            c->sah += (double)c->b->intersect_cost * lanes_wref_blocks(ref) * area(slo, shi);
        } else {
            if (!walk_wide(c, ref, depth + 1)) return false;
            c->slo[k] = c->wlo[ref];
            c->shi[k] = c->whi[ref];
        }
        lo = c->slo[k] < lo ? c->slo[k] : lo;
        hi = c->shi[k] > hi ? c->shi[k] : hi;
        total += c->shi[k] - c->slo[k];
    }
    REQUIRE(filled >= 1, "wide node %u has no children", node);
    REQUIRE(hi - lo == total, "wide node %u does not cover one contiguous range", node);
    c->wlo[node] = lo;
    c->whi[node] = hi;
    c->sah += (double)c->b->traversal_cost * area(blo, bhi);
    return true;
}

typedef struct cut {
    int nslots;
    uint8_t matched[16];
    uint32_t opened[64];   /* BVH2 nodes opened inside this wide node, root excluded */
    int nopened;
} cut;

static bool match_cut(checkw *c, uint32_t wnode, uint32_t d, cut *ct, uint32_t *pairs_w,
                      uint32_t *pairs_b, size_t *npairs)
{
    const lanes_wbvh *w = c->w;
    const lanes_bvh2_node *bd = &c->b->nodes[d];
    const int W = w->width;
    for (int j = 0; j < ct->nslots; j++) {
        size_t k = (size_t)wnode * W + j;
        uint32_t ref = slot_ref(w, wnode, j);
        if (c->slo[k] != c->in->lo[d] || c->shi[k] != c->in->hi[d]) continue;
        REQUIRE(!ct->matched[j], "slot %d of wide node %u matched twice", j, wnode);
        ct->matched[j] = 1;
        float slo[3], shi[3];
        slot_box(w, wnode, j, slo, shi);
        REQUIRE(same_box(slo, shi, bd->min, bd->max),
              "slot %d of wide node %u: bounds differ from BVH2 node %u", j, wnode, d);
        if (lanes_wref_is_leaf(ref)) {
            REQUIRE(bd->count == c->shi[k] - c->slo[k] && bd->first == c->slo[k],
                  "wide leaf (slot %d of %u) is not BVH2 leaf %u", j, wnode, d);
        } else {
            REQUIRE(bd->count == 0, "wide interior slot %d of %u is BVH2 leaf %u", j, wnode, d);
            pairs_w[*npairs] = ref;
            pairs_b[*npairs] = d;
            (*npairs)++;
        }
        return true;
    }
    REQUIRE(bd->count == 0, "BVH2 leaf %u is not a slot of wide node %u", d, wnode);
    REQUIRE(ct->nopened < 64, "wide node %u opens too many nodes", wnode);
    ct->opened[ct->nopened++] = d;
    return match_cut(c, wnode, bd->first, ct, pairs_w, pairs_b, npairs) &&
           match_cut(c, wnode, bd->first + 1, ct, pairs_w, pairs_b, npairs);
}

static bool check_wide(const lanes_bvh2 *b, const bvh2_info *in, const lanes_wbvh *w, int width)
{
    REQUIRE(w->width == width, "width %d, expected %d", w->width, width);
    REQUIRE(w->node_count >= 1 && w->nodes && w->blocks, "empty wide BVH");
    REQUIRE((uintptr_t)w->nodes % 64 == 0 && (uintptr_t)w->blocks % 64 == 0, "wide arrays not 64-byte aligned");
    REQUIRE(lanes_wnode_bytes(width) % 64 == 0 && lanes_wblock_bytes(width) % (4 * (size_t)width < 64 ? 4 * (size_t)width : 64) == 0,
            "nodes or blocks not aligned for a vector of the width");
    REQUIRE(w->prim_count == b->prim_count, "wide BVH holds %zu triangles, the BVH2 %zu", w->prim_count, b->prim_count);
    size_t nslots = w->node_count * (size_t)width, nscene = b->prim_count + b->skipped;
    checkw c = {b, w, in, calloc(w->node_count, 4), calloc(w->node_count, 4), calloc(nslots, 4), calloc(nslots, 4),
                malloc(nscene * 4), calloc(w->node_count, 1), calloc(b->prim_count, 1), calloc(w->block_count, 1),
                0, 0.0};
    uint32_t *pw = malloc(w->node_count * 4), *pb = malloc(w->node_count * 4);
    bool ok = c.wlo && c.whi && c.slo && c.shi && c.pos_of && c.visited && c.cover && c.block_seen && pw && pb;
    if (ok) {
        memset(c.pos_of, 0xff, nscene * 4);
        for (size_t j = 0; j < b->prim_count; j++) c.pos_of[b->prim_index[j]] = (uint32_t)j;
    }
    ok = ok && walk_wide(&c, 0, 1);
    for (size_t i = 0; ok && i < w->node_count; i++)
        if (!c.visited[i]) ok = failf(__LINE__, "wide node %zu unreachable", i);
    for (size_t i = 0; ok && i < w->block_count; i++)
        if (!c.block_seen[i]) ok = failf(__LINE__, "block %zu unreachable", i);
    for (size_t j = 0; ok && j < b->prim_count; j++)
        if (!c.cover[j]) ok = failf(__LINE__, "triangle position %zu not in the wide BVH", j);
    /* Pass 2: node by node against the BVH2, from the root pair (0, 0). */
    size_t np = 0;
    if (ok) {
        pw[0] = 0;
        pb[0] = 0;
        np = 1;
    }
    for (size_t p = 0; ok && p < np; p++) {
        uint32_t wn = pw[p], d = pb[p];
        cut ct;
        memset(&ct, 0, sizeof ct);
        while (ct.nslots < width && !slot_empty(w, wn, ct.nslots)) ct.nslots++;
        const lanes_bvh2_node *bd = &b->nodes[d];
        if (bd->count > 0) {
            /* Only the root can be a leaf. */
            ok = p == 0 && d == 0;
            if (!ok) {
                failf(__LINE__, "wide node %u stands for BVH2 leaf %u", wn, d);
                break;
            }
            ok = match_cut(&c, wn, d, &ct, pw, pb, &np);
        } else {
            ok = match_cut(&c, wn, bd->first, &ct, pw, pb, &np) &&
                 match_cut(&c, wn, bd->first + 1, &ct, pw, pb, &np);
        }
        for (int j = 0; ok && j < ct.nslots; j++)
            if (!ct.matched[j]) ok = failf(__LINE__, "slot %d of wide node %u matches nothing", j, wn);
    }
    if (ok && np != w->node_count) ok = failf(__LINE__, "matched %zu of %zu wide nodes", np, w->node_count);
    if (ok) {
        float rlo[3], rhi[3];
        float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (int j = 0; j < width; j++) {
            if (slot_empty(w, 0, j)) continue;
            slot_box(w, 0, j, rlo, rhi);
            for (int k = 0; k < 3; k++) lo[k] = fminf(lo[k], rlo[k]), hi[k] = fmaxf(hi[k], rhi[k]);
        }
        double ra = area(lo, hi), sah = ra > 0 ? c.sah / ra : 0.0;
        if (!isfinite(sah) || !close_rel(sah, w->sah_cost, 1e-9))
            ok = failf(__LINE__, "wide SAH %.17g, recomputed %.17g", w->sah_cost, sah);
        double s2 = lanes_wbvh_sah(w, b->traversal_cost, b->intersect_cost);
        if (ok && !close_rel(s2, sah, 1e-9))
            ok = failf(__LINE__, "lanes_wbvh_sah %.17g, recomputed %.17g", s2, sah);
        if (ok && c.depth > b->depth) ok = failf(__LINE__, "wide deeper than the BVH2");
        lanes_bvh_stats st;
        if (ok && (!lanes_wbvh_stats(w, b->traversal_cost, b->intersect_cost, &st) ||
                   st.nodes != w->node_count || st.prims != b->prim_count || st.depth != c.depth))
            ok = failf(__LINE__, "wide stats disagree");
    }
    free(c.wlo);
    free(c.whi);
    free(c.slo);
    free(c.shi);
    free(c.pos_of);
    free(c.visited);
    free(c.cover);
    free(c.block_seen);
    free(pw);
    free(pb);
    return ok;
}

/* ------------------------------------------------ collapse optimality */

/* The slots BVH2 node n fills in its wide parent when the nodes in `kept`
 * are wide nodes of their own: one if it is a leaf or kept, else its
 * children's. */
static int brute_slots(const lanes_bvh2 *b, uint32_t n, const uint8_t *kept)
{
    const lanes_bvh2_node *nd = &b->nodes[n];
    if (nd->count > 0 || kept[n]) return 1;
    return brute_slots(b, nd->first, kept) + brute_slots(b, nd->first + 1, kept);
}

/* The least SAH cost of a wide tree of width W over this BVH2's leaves,
 * by trying every set of interior nodes to keep as wide nodes (the root
 * always): a check of the collapse's dynamic programme that shares nothing
 * with it. Normalised by the root's area, as sah_cost is. */
static double brute_optimum(const lanes_bvh2 *b, int W)
{
    size_t nn = b->node_count, ni = 0;
    uint32_t inner[64];
    for (size_t i = 1; i < nn; i++)
        if (b->nodes[i].count == 0) inner[ni++] = (uint32_t)i;
    uint8_t kept[128] = {1};
    double best = INFINITY;
    for (uint64_t mask = 0; mask < (1ull << ni); mask++) {
        for (size_t k = 0; k < ni; k++) kept[inner[k]] = (uint8_t)(mask >> k & 1u);
        bool fits = true;
        double cost = 0.0;
        for (size_t i = 0; i < nn && fits; i++) {
            const lanes_bvh2_node *nd = &b->nodes[i];
            if (nd->count > 0) {
                cost += (double)b->intersect_cost * (double)((nd->count + (uint32_t)W - 1) / (uint32_t)W) *
                        area(nd->min, nd->max);
            } else if (kept[i]) {
                fits = brute_slots(b, nd->first, kept) + brute_slots(b, nd->first + 1, kept) <= W;
                cost += (double)b->traversal_cost * area(nd->min, nd->max);
            }
        }
        if (fits && cost < best) best = cost;
    }
    double ra = area(b->nodes[0].min, b->nodes[0].max);
    return ra > 0.0 ? best / ra : 0.0;
}

/* Small random trees, every width: the collapse's cost is the least one. */
static void collapse_optimality_tests(void)
{
    for (int seed = 1; seed <= 40; seed++) {
        size_t n = 6 + (size_t)seed % 15;
        lanes_scene sc = gen_random(n, (uint64_t)seed + 100);
        lanes_bvh_build_options o;
        lanes_bvh_default_options(&o);
        o.max_leaf_size = 1 + seed % 2;
        o.traversal_cost = seed % 3 == 0 ? 0.3f : 1.0f;
        o.threads = 1;
        snprintf(g_context, sizeof g_context, "optimal collapse n=%zu seed=%d leaf=%d", n, seed,
                 o.max_leaf_size);
        lanes_bvh2 b;
        lanes_error err = {0};
        if (lanes_bvh2_build(&sc, &o, &b, &err) != LANES_OK) {
            CHECK(false, "build failed: %s", err.message);
            free_scene(&sc);
            continue;
        }
        size_t inner = 0;
        for (size_t i = 1; i < b.node_count; i++) inner += b.nodes[i].count == 0;
        for (int W = 4; W <= 16 && inner < 24; W *= 2) {
            lanes_wbvh w;
            if (lanes_wbvh_from_bvh2(&b, W, &w, &err) != LANES_OK) {
                CHECK(false, "collapse to %d failed: %s", W, err.message);
                continue;
            }
            double best = brute_optimum(&b, W);
            CHECK(close_rel(w.sah_cost, best, 1e-12), "%s width %d: collapse cost %.17g, least cost %.17g",
                  g_context, W, w.sah_cost, best);
            lanes_wbvh_free(&w);
        }
        CHECK(inner < 24, "tree of %zu interior nodes too large to search", inner);
        lanes_bvh2_free(&b);
        free_scene(&sc);
    }
}

/* -------------------------------------------------------------- drivers */

static bool same_bvh2(const lanes_bvh2 *a, const lanes_bvh2 *b)
{
    if (a->node_count != b->node_count || a->prim_count != b->prim_count || a->depth != b->depth ||
        a->sah_cost != b->sah_cost)
        return false;
    if (memcmp(a->nodes, b->nodes, a->node_count * sizeof *a->nodes)) return false;
    if (memcmp(a->prim_index, b->prim_index, a->prim_count * sizeof *a->prim_index)) return false;
    const float *fa[9] = {a->tris.v0x, a->tris.v0y, a->tris.v0z, a->tris.v1x, a->tris.v1y,
                          a->tris.v1z, a->tris.v2x, a->tris.v2y, a->tris.v2z};
    const float *fb[9] = {b->tris.v0x, b->tris.v0y, b->tris.v0z, b->tris.v1x, b->tris.v1y,
                          b->tris.v1z, b->tris.v2x, b->tris.v2y, b->tris.v2z};
    for (int k = 0; k < 9; k++)
        if (memcmp(fa[k], fb[k], a->prim_count * sizeof(float))) return false;
    return true;
}

static bool same_wide(const lanes_wbvh *a, const lanes_wbvh *b)
{
    return a->width == b->width && a->node_count == b->node_count && a->block_count == b->block_count &&
           a->sah_cost == b->sah_cost &&
           !memcmp(a->nodes, b->nodes, a->node_count * lanes_wnode_bytes(a->width)) &&
           !memcmp(a->blocks, b->blocks, a->block_count * lanes_wblock_bytes(a->width));
}

static void print_stats(const char *name, const lanes_bvh2 *b, const lanes_wbvh w[3])
{
    lanes_bvh_stats s;
    lanes_bvh2_stats(b, b->traversal_cost, b->intersect_cost, &s);
    printf("  %-12s %8zu tris (%zu skipped): bvh2 %zu nodes, %zu leaves, avg leaf %.2f, depth %d, "
           "SAH %.3f, %.2f MB, %.1f ms\n",
           name, b->prim_count, b->skipped, s.nodes, s.leaves, s.avg_leaf_size, s.depth,
           s.sah_cost, s.bytes / 1e6, b->build_seconds * 1e3);
    for (int i = 0; i < 3; i++) {
        lanes_bvh_stats t;
        lanes_wbvh_stats(&w[i], b->traversal_cost, b->intersect_cost, &t);
        printf("  %-12s   w%-2d %zu nodes, %.2f children/node, %zu leaves, depth %d, SAH %.3f, "
               "%.2f MB, %.1f ms\n",
               "", w[i].width, t.nodes, t.avg_children, t.leaves, t.depth, t.sah_cost,
               t.bytes / 1e6, w[i].collapse_seconds * 1e3);
    }
}

/* Builds with each thread count in `threads`, checks every result, and
 * checks they are identical; then collapses and checks each width. */
static void run_scene(const lanes_scene *sc, const lanes_bvh_build_options *base,
                      const int *threads, int nthreads, bool print)
{
    lanes_bvh2 ref;
    memset(&ref, 0, sizeof ref);
    bool have_ref = false;
    lanes_wbvh wref[3];
    memset(wref, 0, sizeof wref);
    for (int ti = 0; ti < nthreads; ti++) {
        lanes_bvh_build_options o = *base;
        o.threads = threads[ti];
        snprintf(g_context, sizeof g_context, "%s n=%zu bins=%d leaf=%d threads=%d", sc->name,
                 sc->triangle_count, o.bins, o.max_leaf_size, o.threads);
        lanes_bvh2 b;
        lanes_error err = {0};
        if (lanes_bvh2_build(sc, &o, &b, &err) != LANES_OK) {
            CHECK(false, "build failed: %s", err.message);
            continue;
        }
        bvh2_info in;
        bool ok2 = check_bvh2(sc, &b, &o, &in);
        CHECK(ok2, "BVH2 check failed");
        /* The wide checks lean on what the BVH2 check learnt. */
        for (int wi = 0; wi < 3 && ok2; wi++) {
            lanes_wbvh w;
            if (lanes_wbvh_from_bvh2(&b, 4 << wi, &w, &err) != LANES_OK) {
                CHECK(false, "collapse to %d failed: %s", 4 << wi, err.message);
                continue;
            }
            snprintf(g_context + strlen(g_context), sizeof g_context - strlen(g_context), " w%d",
                     4 << wi);
            CHECK(check_wide(&b, &in, &w, 4 << wi), "wide check failed");
            *strrchr(g_context, ' ') = 0;
            if (!have_ref) {
                wref[wi] = w;
            } else {
                CHECK(same_wide(&w, &wref[wi]), "wide %d differs from threads=%d's", 4 << wi,
                       threads[0]);
                lanes_wbvh_free(&w);
            }
        }
        info_free(&in);
        if (!have_ref) {
            ref = b;
            have_ref = true;
            if (print) print_stats(sc->name, &ref, wref);
        } else {
            CHECK(same_bvh2(&b, &ref), "tree differs from threads=%d's", threads[0]);
            lanes_bvh2_free(&b);
        }
    }
    if (have_ref) lanes_bvh2_free(&ref);
    for (int i = 0; i < 3; i++) lanes_wbvh_free(&wref[i]);
}

/* The checkers must reject broken trees. */
static void negative_tests(void)
{
    snprintf(g_context, sizeof g_context, "negative");
    lanes_scene sc = gen_random(3000, 9);
    lanes_bvh_build_options o;
    lanes_bvh_default_options(&o);
    lanes_bvh2 b;
    lanes_error err;
    if (lanes_bvh2_build(&sc, &o, &b, &err) != LANES_OK) {
        CHECK(false, "build failed: %s", err.message);
        free_scene(&sc);
        return;
    }
    lanes_wbvh w;
    lanes_wbvh_from_bvh2(&b, 8, &w, &err);
    bvh2_info in;
    CHECK(check_bvh2(&sc, &b, &o, &in), "unmodified tree rejected");
    CHECK(check_wide(&b, &in, &w, 8), "unmodified wide tree rejected");

    size_t leaf = 0, inner = 0;
    for (size_t i = 1; i < b.node_count; i++) {
        if (b.nodes[i].count > 0 && !leaf) leaf = i;
        if (b.nodes[i].count == 0 && !inner) inner = i;
    }
    struct {
        const char *what;
        float *f;
        float v;
    } pokes[] = {
        {"leaf bound loosened", &b.nodes[leaf].min[0], nextafterf(b.nodes[leaf].min[0], -INFINITY)},
        {"interior bound loosened", &b.nodes[inner].max[1],
         nextafterf(b.nodes[inner].max[1], INFINITY)},
        {"leaf bound shrunk", &b.nodes[leaf].max[2], nextafterf(b.nodes[leaf].max[2], -INFINITY)},
        {"triangle moved", &b.tris.v1y[b.nodes[leaf].first], b.tris.v1y[b.nodes[leaf].first] + 1},
    };
    g_quiet = true;
    for (size_t i = 0; i < sizeof pokes / sizeof pokes[0]; i++) {
        float keep = *pokes[i].f;
        *pokes[i].f = pokes[i].v;
        bvh2_info bad;
        bool accepted = check_bvh2(&sc, &b, &o, &bad);
        info_free(&bad);
        *pokes[i].f = keep;
        g_quiet = false;
        CHECK(!accepted, "checker accepted: %s", pokes[i].what);
        g_quiet = true;
    }
    /* Swapped leaf order; a leaf count cut short. */
    uint32_t t = b.prim_index[0];
    b.prim_index[0] = b.prim_index[1];
    b.prim_index[1] = t;
    bvh2_info bad;
    bool accepted = check_bvh2(&sc, &b, &o, &bad);
    info_free(&bad);
    b.prim_index[1] = b.prim_index[0];
    b.prim_index[0] = t;
    g_quiet = false;
    CHECK(!accepted, "checker accepted swapped prim_index");
    g_quiet = true;
    b.nodes[leaf].count--;
    accepted = b.nodes[leaf].count > 0 && check_bvh2(&sc, &b, &o, &bad);
    info_free(&bad);
    b.nodes[leaf].count++;
    g_quiet = false;
    CHECK(!accepted, "checker accepted a shortened leaf");
    g_quiet = true;

    /* Wide: an empty slot with a box; a child box differing by an ulp; two
     * slots swapped in the child array. */
    size_t empty_node = SIZE_MAX;
    int empty_slot = 0;
    for (size_t i = 0; i < w.node_count && empty_node == SIZE_MAX; i++)
        for (int j = 0; j < 8; j++)
            if (slot_empty(&w, i, j)) {
                empty_node = i;
                empty_slot = j;
                break;
            }
    float *pf[3] = {
        (float *)plane(&w, 0, 0),
        empty_node != SIZE_MAX ? (float *)plane(&w, empty_node, 3) + empty_slot : NULL,
        (float *)plane(&w, 0, 4) + 1};
    for (int i = 0; i < 3; i++) {
        if (!pf[i]) continue;
        float keep = *pf[i];
        *pf[i] = i == 1 ? 0.0f : nextafterf(keep, i == 0 ? -INFINITY : INFINITY);
        accepted = check_wide(&b, &in, &w, 8);
        *pf[i] = keep;
        g_quiet = false;
        CHECK(!accepted, "wide checker accepted corruption %d", i);
        g_quiet = true;
    }
    uint32_t *ref0 = (uint32_t *)lanes_wnode_refs(&w, 0);
    uint32_t c0 = ref0[0];
    ref0[0] = ref0[1];
    ref0[1] = c0;
    accepted = check_wide(&b, &in, &w, 8);
    ref0[1] = ref0[0];
    ref0[0] = c0;
    g_quiet = false;
    CHECK(!accepted, "wide checker accepted swapped children");
    g_quiet = true;
    /* A leaf block: one vertex coordinate an ulp off; a prim index changed. */
    float *v0 = (float *)lanes_wblock_verts(&w, 0);
    uint32_t *p0 = (uint32_t *)lanes_wblock_prims(&w, 0);
    int lane = isnan(v0[0]) ? 1 : 0;
    float keepv = v0[lane];
    v0[lane] = nextafterf(keepv, INFINITY);
    accepted = check_wide(&b, &in, &w, 8);
    v0[lane] = keepv;
    g_quiet = false;
    CHECK(!accepted, "wide checker accepted a changed vertex");
    g_quiet = true;
    uint32_t keepp = p0[0];
    p0[0] = p0[0] == 0 ? 1 : p0[0] - 1;
    accepted = check_wide(&b, &in, &w, 8);
    p0[0] = keepp;
    g_quiet = false;
    CHECK(!accepted, "wide checker accepted a changed prim index");
    CHECK(check_wide(&b, &in, &w, 8), "restored wide tree rejected");
    info_free(&in);
    lanes_wbvh_free(&w);
    lanes_bvh2_free(&b);
    free_scene(&sc);
}

static void error_tests(void)
{
    snprintf(g_context, sizeof g_context, "errors");
    lanes_bvh_build_options o;
    lanes_bvh2 b;
    lanes_error err;
    lanes_scene sc = gen_random(10, 3);
    struct {
        int bins, leaf, threads;
        float ct;
    } bad[] = {{1, 4, 0, 1}, {257, 4, 0, 1}, {16, 0, 0, 1}, {16, 4, -1, 1}, {16, 4, 0, -1},
               {16, 4, 0, NAN}, {16, 4, 0, 1}, {16, 4, 0, 1}};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        lanes_bvh_default_options(&o);
        o.bins = bad[i].bins;
        o.max_leaf_size = bad[i].leaf;
        o.threads = bad[i].threads;
        o.traversal_cost = bad[i].ct;
        if (i >= 6) o.sah_block = i == 6 ? 0 : 65;
        err.message[0] = 0;
        CHECK(lanes_bvh2_build(&sc, &o, &b, &err) != LANES_OK && err.message[0], "bad option %zu accepted",
               i);
    }
    lanes_bvh_default_options(&o);
    for (size_t i = 0; i < 10; i++) sc.verts[9 * i + 4] = NAN;
    err.message[0] = 0;
    CHECK(lanes_bvh2_build(&sc, &o, &b, &err) != LANES_OK && err.message[0], "all-NaN scene accepted");
    CHECK(b.skipped == 10, "all-NaN scene: skipped %zu", b.skipped);
    sc.triangle_count = 0;
    CHECK(lanes_bvh2_build(&sc, &o, &b, &err) != LANES_OK, "empty scene accepted");
    free_scene(&sc);
    lanes_wbvh w;
    CHECK(lanes_wbvh_from_bvh2(&b, 4, &w, &err) != LANES_OK, "collapse of an empty BVH2 accepted");
    sc = gen_random(100, 3);
    lanes_bvh2_build(&sc, &o, &b, &err);
    CHECK(lanes_wbvh_from_bvh2(&b, 6, &w, &err) != LANES_OK, "width 6 accepted");
    /* Malformed trees end in an error, not a hang or a crash: a cycle
     * (the root is its own child), a child index out of range, a leaf
     * past the triangles. */
    lanes_bvh_stats st;
    uint32_t first = b.nodes[0].first;
    uint32_t bad_first[3] = {0, (uint32_t)b.node_count - 1, UINT32_MAX};
    for (int i = 0; i < 3; i++) {
        b.nodes[0].first = bad_first[i];
        err.message[0] = 0;
        CHECK(lanes_wbvh_from_bvh2(&b, 8, &w, &err) != LANES_OK && err.message[0],
               "collapse accepted a malformed tree (%d)", i);
        CHECK(!lanes_bvh2_stats(&b, 1, 1, &st), "stats accepted a malformed tree (%d)", i);
        CHECK(isnan(lanes_bvh2_sah(&b, 1, 1)), "SAH of a malformed tree (%d)", i);
    }
    b.nodes[0].first = first;
    size_t leaf = 1;
    while (b.nodes[leaf].count == 0) leaf++;
    b.nodes[leaf].count += (uint32_t)b.prim_count;
    CHECK(lanes_wbvh_from_bvh2(&b, 4, &w, &err) != LANES_OK, "collapse accepted a leaf past the end");
    b.nodes[leaf].count -= (uint32_t)b.prim_count;
    CHECK(lanes_wbvh_from_bvh2(&b, 4, &w, &err) == LANES_OK, "restored tree rejected: %s", err.message);
    lanes_wbvh_free(&w);
    lanes_bvh2_free(&b);
    free_scene(&sc);
}

/* ---------------------------------------------------------- OFF meshes */

static bool next_line(char **p, char **line)
{
    while (**p) {
        char *s = *p, *e = strchr(s, '\n');
        if (e) *e = 0, *p = e + 1;
        else *p = s + strlen(s);
        char *h = strchr(s, '#');
        if (h) *h = 0;
        while (*s == ' ' || *s == '\t' || *s == '\r') s++;
        if (*s) {
            *line = s;
            return true;
        }
    }
    return false;
}

/* A small reader for the plain OFF the CGAL data sets use; polygons are
 * split into fans. Returns false with a reason. */
static bool read_off(const char *path, lanes_scene *sc, char *why, size_t whylen)
{
    FILE *f = fopen(path, "rb");
    if (!f) return snprintf(why, whylen, "cannot open"), false;
    fseek(f, 0, SEEK_END);
    long len = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *text = malloc((size_t)len + 1);
    if (!text || fread(text, 1, (size_t)len, f) != (size_t)len) {
        fclose(f);
        free(text);
        return snprintf(why, whylen, "cannot read"), false;
    }
    fclose(f);
    text[len] = 0;
    char *p = text, *line;
    long nv = -1, nf = -1;
    float *v = NULL;
    bool ok = next_line(&p, &line) && !strncmp(line, "OFF", 3);
    if (ok) {
        line += 3;
        while (*line == ' ' || *line == '\t') line++;
        if (!*line) ok = next_line(&p, &line);
        ok = ok && sscanf(line, "%ld %ld", &nv, &nf) == 2 && nv > 0 && nf > 0 && nv < (1L << 28) &&
             nf < (1L << 28);
    }
    if (!ok) {
        free(text);
        return snprintf(why, whylen, "not an OFF file"), false;
    }
    v = malloc((size_t)nv * 3 * sizeof(float));
    for (long i = 0; ok && i < nv; i++)
        ok = next_line(&p, &line) && sscanf(line, "%f %f %f", &v[3 * i], &v[3 * i + 1], &v[3 * i + 2]) == 3;
    size_t cap = (size_t)nf * 2, n = 0;
    float *t = malloc(cap * 9 * sizeof(float));
    for (long i = 0; ok && i < nf; i++) {
        ok = next_line(&p, &line);
        char *s = line, *e;
        long k = ok ? strtol(s, &e, 10) : 0;
        if (!ok || k < 3 || k > 1000) {
            ok = false;
            break;
        }
        s = e;
        long idx[1000];
        for (long j = 0; ok && j < k; j++) {
            idx[j] = strtol(s, &e, 10);
            ok = e != s && idx[j] >= 0 && idx[j] < nv;
            s = e;
        }
        for (long j = 1; ok && j + 1 < k; j++) {
            if (n == cap) {
                cap *= 2;
                float *q = realloc(t, cap * 9 * sizeof(float));
                if (!q) {
                    ok = false;
                    break;
                }
                t = q;
            }
            long tri[3] = {idx[0], idx[j], idx[j + 1]};
            for (int m = 0; m < 3; m++) memcpy(t + 9 * n + 3 * m, v + 3 * tri[m], 12);
            n++;
        }
    }
    free(text);
    free(v);
    if (!ok) {
        free(t);
        return snprintf(why, whylen, "malformed vertex or face"), false;
    }
    memset(sc, 0, sizeof *sc);
    const char *base = strrchr(path, '/');
    base = base ? base + 1 : path;
    size_t bl = strlen(base) < sizeof sc->name - 1 ? strlen(base) : sizeof sc->name - 1;
    memcpy(sc->name, base, bl);
    sc->name[bl] = 0;
    sc->verts = t;
    sc->triangle_count = n;
    return true;
}

static int cmp_name(const void *a, const void *b) { return strcmp(a, b); }

static int run_meshes(void)
{
    const char *env = getenv("LANES_MESH_DIR");
    char dirs[4096];
    snprintf(dirs, sizeof dirs, "%s", env && *env ? env : LANES_DEFAULT_MESH_DIRS);
    int found = 0;
    const int threads[] = {0, 1};
    lanes_bvh_build_options o;
    lanes_bvh_default_options(&o);
    for (char *d = strtok(dirs, ":"); d; d = strtok(NULL, ":")) {
        DIR *dir = opendir(d);
        if (!dir) continue;
        struct dirent *e;
        char names[256][256];
        int nn = 0;
        while ((e = readdir(dir)) && nn < 256) {
            size_t l = strlen(e->d_name);
            if (l > 4 && !strcmp(e->d_name + l - 4, ".off"))
                snprintf(names[nn++], sizeof names[0], "%s", e->d_name);
        }
        closedir(dir);
        qsort(names, (size_t)nn, sizeof names[0], cmp_name);
        for (int i = 0; i < nn; i++) {
            char path[4096], why[128];
            if (snprintf(path, sizeof path, "%s/%s", d, names[i]) >= (int)sizeof path) continue;
            lanes_scene sc;
            if (!read_off(path, &sc, why, sizeof why)) {
                printf("  %s: not read (%s), skipped\n", path, why);
                continue;
            }
            found++;
            run_scene(&sc, &o, threads, 2, true);
            free_scene(&sc);
        }
    }
    if (!found) {
        printf("no .off meshes in %s: skipped\n", env && *env ? env : LANES_DEFAULT_MESH_DIRS);
        return 77;
    }
    printf("%d meshes\n", found);
    return harness_summary("test_bvh meshes");
}

int main(int argc, char **argv)
{
    if (argc > 1 && !strcmp(argv[1], "--meshes")) return run_meshes();
    if (argc > 1) {
        fprintf(stderr, "usage: %s [--meshes]\n", argv[0]);
        return 2;
    }
    double t0 = now();
    lanes_bvh_build_options o;
    lanes_bvh_default_options(&o);
    const int threads[] = {1, 2, 4};

    lanes_scene sc = gen_random(1, 1);
    snprintf(sc.name, sizeof sc.name, "one");
    run_scene(&sc, &o, threads, 3, true);
    free_scene(&sc);
    sc = gen_random(2, 2);
    snprintf(sc.name, sizeof sc.name, "two");
    run_scene(&sc, &o, threads, 3, true);
    free_scene(&sc);

    sc = gen_random(50000, 1);
    run_scene(&sc, &o, threads, 3, true);
    const struct {
        int bins, leaf, block;
        float ct, ci;
    } variants[] = {{2, 4, 1, 1, 1},   {32, 4, 1, 1, 1},  {256, 4, 1, 1, 1}, {16, 1, 1, 1, 1},
                    {16, 8, 1, 1, 1},  {16, 16, 1, 1, 1}, {16, 4, 1, 0, 1},  {16, 4, 1, 3, 0.5f},
                    {16, 4, 4, 1, 1},  {16, 8, 8, 1, 1},  {16, 16, 16, 1, 1}, {16, 16, 8, 1, 1}};
    for (size_t i = 0; i < sizeof variants / sizeof variants[0]; i++) {
        lanes_bvh_build_options v = o;
        v.bins = variants[i].bins;
        v.max_leaf_size = variants[i].leaf;
        v.sah_block = variants[i].block;
        v.traversal_cost = variants[i].ct;
        v.intersect_cost = variants[i].ci;
        run_scene(&sc, &v, threads, 2, false);
    }
    free_scene(&sc);

    sc = gen_grid(200, 200);
    run_scene(&sc, &o, threads, 3, true);
    free_scene(&sc);
    sc = gen_sphere(150, 200);
    run_scene(&sc, &o, threads, 3, true);
    free_scene(&sc);
    sc = gen_same(100000);
    run_scene(&sc, &o, threads, 3, true);
    free_scene(&sc);
    size_t spoiled;
    sc = gen_nan_mixed(30000, &spoiled);
    run_scene(&sc, &o, threads, 3, true);
    free_scene(&sc);
    sc = gen_geometric(20000);
    run_scene(&sc, &o, threads, 3, true);
    free_scene(&sc);
    sc = gen_extreme();
    run_scene(&sc, &o, threads, 3, true);
    free_scene(&sc);

    collapse_optimality_tests();
    negative_tests();
    error_tests();
    printf("%.1f s\n", now() - t0);
    return harness_summary("test_bvh");
}
