/* Binned SAH builder for the binary BVH.
 *
 * The build runs in four phases, each a parallel loop over work items whose
 * boundaries depend only on the input, never on the thread count, so every
 * thread count produces the same bytes:
 *
 *  0. Primitive references (bounds of each triangle) in blocks of BLOCK
 *     triangles; non-finite triangles are dropped by a stable compaction.
 *  1. The top of the tree, breadth first. Every node larger than the task
 *     size is split with all threads at once: per block binning, a serial
 *     SAH sweep per node, then a stable out-of-place partition (count,
 *     prefix sum, scatter) into the other of two reference buffers. One
 *     level costs three fork-joins whatever the number of nodes on it.
 *  2. Each node at or below the task size becomes a task: a serial
 *     recursive build with in-place partitioning into the node buffer of
 *     whichever thread runs it.
 *  3. Assembly: the top nodes first, then the tasks' nodes in task order
 *     (an order fixed by phase 1), with child indices rebased; the
 *     triangles are gathered into leaf order alongside.
 *
 * Bounds only ever pass through min and max of the input floats, so every
 * node box is the exact union of its triangles' vertex boxes. Bin counts and
 * min/max merges are exact and order-independent; the SAH sweeps run
 * serially per node; so nothing depends on which thread binned what.
 *
 * Compiled for the x86-64 baseline. */
#define _POSIX_C_SOURCE 200809L

#include "build/bvh.h"
#include "build/bvh_alloc.h"
#include "build/grow_array.h"
#include "build/parallel.h"

#include <float.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

enum {
    MAX_BINS = 256,
    MAX_THREADS = LANES_PARALLEL_MAX_THREADS,
    /* Work item of phases 0 and 1: big enough to amortise a fetch from the
     * shared counter, small enough to balance two to a few dozen threads. */
    BLOCK = 4096,
    /* Nodes up to this size (or N / TASK_DIV, if larger) are built serially
     * by one thread. In-place serial partitioning moves less memory than
     * the stable scatter of phase 1, so tasks are kept as large as load
     * balancing allows: N / 64 leaves 64 to 128 tasks, plenty for 2 to 16
     * threads when the largest go first (N / 256 measured 2-3% slower on
     * 2 cores at 3M triangles, N / 32 no faster). */
    TASK_MIN = 4096,
    TASK_DIV = 64,
};

/* 32 bytes: two of them per cache line. */
typedef struct prim_ref {
    float lo[3];
    uint32_t id;
    float hi[3];
    uint32_t valid;
} prim_ref;

typedef struct aabb {
    float lo[3], hi[3];
} aabb;

/* A bin's box with each corner padded to four floats (lane 3 always 0), so
 * that binning grows it with one 4-wide min and one max (f4 below); 48
 * bytes, 16-byte aligned, so that no corner straddles two cache lines. */
typedef struct bin {
    _Alignas(16) float lo[4];
    float hi[4];
    uint32_t n;
} bin;

/* x86 minss/maxss compute exactly these, so the compiler emits them. */
static inline float fmin_(float a, float b) { return a < b ? a : b; }
static inline float fmax_(float a, float b) { return a > b ? a : b; }

static inline void aabb_empty(aabb *b)
{
    for (int a = 0; a < 3; a++) {
        b->lo[a] = INFINITY;
        b->hi[a] = -INFINITY;
    }
}

static inline void aabb_grow(aabb *b, const float lo[3], const float hi[3])
{
    for (int a = 0; a < 3; a++) {
        b->lo[a] = fmin_(b->lo[a], lo[a]);
        b->hi[a] = fmax_(b->hi[a], hi[a]);
    }
}

static inline void aabb_merge(aabb *b, const aabb *o) { aabb_grow(b, o->lo, o->hi); }

/* Centroids are kept doubled (lo + hi): binning only needs their order and
 * spacing, and this saves a multiply per axis per reference per level. */
static inline void centroid2(const prim_ref *r, float c[3])
{
    for (int a = 0; a < 3; a++) c[a] = r->lo[a] + r->hi[a];
}

static inline void aabb_grow_point(aabb *b, const float c[3]) { aabb_grow(b, c, c); }

/* Half the surface area, in double for the reported cost. */
static inline double half_area_d(const aabb *b)
{
    double dx = (double)b->hi[0] - b->lo[0], dy = (double)b->hi[1] - b->lo[1],
           dz = (double)b->hi[2] - b->lo[2];
    if (!(dx >= 0.0 && dy >= 0.0 && dz >= 0.0)) return 0.0;
    return dx * dy + dy * dz + dz * dx;
}

/* Half the surface area of a box of these extents; an empty box has none. */
static inline float extent_half_area(float dx, float dy, float dz)
{
    if (!(dx >= 0.0f && dy >= 0.0f && dz >= 0.0f)) return 0.0f;
    return dx * dy + dy * dz + dz * dx;
}

static inline float half_area(const aabb *b)
{
    return extent_half_area(b->hi[0] - b->lo[0], b->hi[1] - b->lo[1], b->hi[2] - b->lo[2]);
}

static int ceil_log2(size_t n)
{
    int k = 0;
    while (((size_t)1 << k) < n) k++;
    return k;
}

/* ------------------------------------------------------------------------
 * Binning and the SAH sweep, shared by phases 1 and 2. */

typedef struct binner {
    float cmin[4], scale[4]; /* lane 3 is 0: see bin_one */
    bool ok[3];  /* the axis has a usable centroid extent */
    float kmax;  /* bins - 1 */
    int bins;
} binner;

/* Returns false when no axis can be binned (all centroids coincide, or
 * their extent is too small or too large to scale). */
static bool binner_init(binner *bn, const aabb *cent, int bins)
{
    bool any = false;
    bn->bins = bins;
    bn->kmax = (float)(bins - 1);
    bn->cmin[3] = bn->scale[3] = 0.0f;
    for (int a = 0; a < 3; a++) {
        float ext = cent->hi[a] - cent->lo[a];
        float s = (float)bins / ext;
        bn->cmin[a] = cent->lo[a];
        bn->ok[a] = ext > 0.0f && s > 0.0f && s <= FLT_MAX;
        bn->scale[a] = bn->ok[a] ? s : 0.0f;
        any |= bn->ok[a];
    }
    return any;
}

/* Every centroid of a node is >= the node's cmin (both come from the same
 * float additions), so f >= 0 and only the upper clamp is needed. f is NaN
 * only on an unusable axis whose centroids overflowed (inf * 0); the
 * comparison sends NaN to the last bin. The clamp comes before the
 * conversion, which is undefined for values out of int's range. Binning
 * and partitioning both call this, so they agree on every reference. */
static inline int bin_index(float c, float cmin, float scale, float kmax)
{
    float f = (c - cmin) * scale;
    f = f < kmax ? f : kmax;
    return (int)f;
}

static void bins_clear(bin *bins, int count)
{
    for (int i = 0; i < count; i++) {
        for (int a = 0; a < 3; a++) {
            bins[i].lo[a] = INFINITY;
            bins[i].hi[a] = -INFINITY;
        }
        bins[i].lo[3] = bins[i].hi[3] = 0.0f;
        bins[i].n = 0;
    }
}

/* Binning is the builder's hottest loop, and as scalar code it updates
 * each bin's six bounds one minss or maxss at a time. GCC and clang vector
 * extensions (baseline SSE2 on x86-64, no intrinsics headers) do one 4-wide
 * min and max per bin. The selects compute exactly fmin_/fmax_ per lane,
 * so the bins, and the tree, are bitwise the same as the scalar code's. */
typedef float f4 __attribute__((vector_size(16)));
typedef int32_t i4 __attribute__((vector_size(16)));

static inline f4 f4_load(const float *p)
{
    f4 v;
    memcpy(&v, p, sizeof v);
    return v;
}

static inline void f4_store(float *p, f4 v) { memcpy(p, &v, sizeof v); }
static inline f4 f4_select(i4 m, f4 a, f4 b) { return (f4)(((i4)a & m) | ((i4)b & ~m)); }
static inline f4 f4_min(f4 a, f4 b) { return f4_select(a < b, a, b); }
static inline f4 f4_max(f4 a, f4 b) { return f4_select(a > b, a, b); }

/* Grows the box (lo, hi) by bin b's; the current box is min's and max's
 * first operand, as it was aabb_grow's. */
static inline void box_add_bin(f4 *lo, f4 *hi, const bin *b)
{
    *lo = f4_min(*lo, f4_load(b->lo));
    *hi = f4_max(*hi, f4_load(b->hi));
}

static inline void bin_add_box(bin *t, f4 lo, f4 hi)
{
    f4_store(t->lo, f4_min(f4_load(t->lo), lo));
    f4_store(t->hi, f4_max(f4_load(t->hi), hi));
}

static inline void bin_grow(bin *t, f4 lo, f4 hi)
{
    bin_add_box(t, lo, hi);
    t->n++;
}

static inline void bin_one(const binner *bn, const prim_ref *p, bin *bx, bin *by, bin *bz)
{
    /* A reference's corners with lane 3 (the id and the valid flag) zeroed:
     * read as floats, the flag and ids below 2^23 are denormals, which
     * would slow the arithmetic below on some CPUs. */
    const i4 xyz = {-1, -1, -1, 0};
    const unsigned char *bytes = (const unsigned char *)p;
    f4 lo, hi;
    memcpy(&lo, bytes + offsetof(prim_ref, lo), sizeof lo);
    memcpy(&hi, bytes + offsetof(prim_ref, hi), sizeof hi);
    lo = (f4)((i4)lo & xyz);
    hi = (f4)((i4)hi & xyz);
    /* bin_index per lane; lane 3 is (0 - 0) * 0 = 0 */
    const f4 kmax = {bn->kmax, bn->kmax, bn->kmax, bn->kmax};
    f4 f = (lo + hi - f4_load(bn->cmin)) * f4_load(bn->scale);
    i4 k = __builtin_convertvector(f4_select(f < kmax, f, kmax), i4);
    bin_grow(&bx[k[0]], lo, hi);
    bin_grow(&by[k[1]], lo, hi);
    bin_grow(&bz[k[2]], lo, hi);
}

/* half_area of a box held as two f4 */
static inline float bin_half_area(f4 lo, f4 hi)
{
    f4 d = hi - lo;
    return extent_half_area(d[0], d[1], d[2]);
}

static void bins_merge(bin *dst, const bin *src, int count)
{
    for (int i = 0; i < count; i++) {
        bin_add_box(&dst[i], f4_load(src[i].lo), f4_load(src[i].hi));
        dst[i].n += src[i].n;
    }
}

/* Fills bins (3 axes x bn->bins, cleared here). Clearing all of them
 * costs less than resetting only the filled ones: stores are cheap, and
 * the test of each bin's count is a branch the CPU cannot predict. */
static void bin_refs(const binner *bn, const prim_ref *r, size_t n, bin *bins)
{
    const int K = bn->bins;
    bins_clear(bins, 3 * K);
    for (size_t i = 0; i < n; i++) bin_one(bn, &r[i], bins, bins + K, bins + 2 * K);
}

/* A split plane, and everything the partition needs to apply it. */
typedef struct split {
    int axis;
    int mid;         /* left iff bin < mid */
    float cmin, scale, kmax; /* the binner's, for the axis */
    float cost;      /* nL * A(L) + nR * A(R), half areas */
} split;

/* Leaf cost units of n triangles: blocks of `block` (1: per triangle). */
static inline uint32_t sah_blocks(uint32_t n, uint32_t block) { return (n + block - 1) / block; }

/* Best SAH split over the usable axes; false when every candidate leaves a
 * side empty or costs infinity (boxes too large to measure in float). The
 * sweeps skip empty bins: a small node fills few of them, and splitting
 * anywhere between two filled bins gives the same partition. The first
 * minimum wins, axis by axis, so the choice is deterministic. */
static bool find_split(const binner *bn, const bin *bins, uint32_t block, split *out)
{
    const int K = bn->bins;
    float rarea[MAX_BINS];
    uint32_t rcount[MAX_BINS];
    uint8_t used[MAX_BINS];
    float best = INFINITY;
    bool found = false;
    for (int a = 0; a < 3; a++) {
        if (!bn->ok[a]) continue;
        const bin *b = bins + a * K;
        int m = 0;
        for (int k = 0; k < K; k++) {
            used[m] = (uint8_t)k;
            m += b[k].n != 0;
        }
        if (m < 2) continue;
        const bin *last = &b[used[m - 1]];
        f4 lo = f4_load(last->lo), hi = f4_load(last->hi);
        uint32_t n = last->n;
        rarea[m - 1] = bin_half_area(lo, hi);
        rcount[m - 1] = n;
        for (int t = m - 2; t > 0; t--) {
            box_add_bin(&lo, &hi, &b[used[t]]);
            n += b[used[t]].n;
            rarea[t] = bin_half_area(lo, hi);
            rcount[t] = n;
        }
        lo = f4_load(b[used[0]].lo), hi = f4_load(b[used[0]].hi);
        n = 0;
        for (int t = 1; t < m; t++) {
            if (t > 1) box_add_bin(&lo, &hi, &b[used[t - 1]]);
            n += b[used[t - 1]].n;
            float cost = (float)sah_blocks(n, block) * bin_half_area(lo, hi) + (float)sah_blocks(rcount[t], block) * rarea[t];
            if (cost < best) {
                best = cost;
                out->axis = a;
                out->mid = used[t];
                out->cmin = bn->cmin[a];
                out->scale = bn->scale[a];
                out->kmax = bn->kmax;
                out->cost = cost;
                found = true;
            }
        }
    }
    return found;
}

static inline bool goes_left(const split *s, const prim_ref *r)
{
    int a = s->axis;
    return bin_index(r->lo[a] + r->hi[a], s->cmin, s->scale, s->kmax) < s->mid;
}

/* ------------------------------------------------------------------------
 * Builder state. */

typedef struct worker {
    bin *bins;                 /* 3 * bins, phase 2 */
    lanes_bvh2_node *nodes;    /* phase 2 output of the tasks this thread ran */
    size_t count, cap;
} worker;

/* A subtree built serially in phase 2. */
typedef struct task {
    uint32_t begin, end;
    uint32_t slot;            /* final index of its root (a top-level slot) */
    int level;                /* of its root; the tree's root is level 1 */
    int buf;                  /* which reference buffer holds its range */
    aabb geo, cent;
    /* results */
    int tid;
    size_t start, count;      /* its nodes in workers[tid].nodes */
    size_t offset;            /* final index of its second node */
    int depth;
    double sah;               /* unnormalised partial sum */
} task;

/* A node being split in phase 1. */
typedef struct tnode {
    uint32_t begin, end, slot;
    int level;
    aabb geo, cent;
    binner bn;
    bool sah;                 /* false: split at the middle of the range */
    split s;
    size_t blk0, nblk;
    uint32_t nleft;
} tnode;

typedef struct tblock {
    size_t node;
    uint32_t begin, end;
    uint32_t nl;
    aabb lg, lc, rg, rc;      /* geometry and centroid bounds of both sides */
    uint32_t ldst, rdst;
} tblock;

typedef struct builder {
    const lanes_scene *scene;
    int bins, maxleaf;
    uint32_t block;          /* SAH leaf cost per block of this many triangles */
    float ct, ci;
    uint32_t task_size;
    size_t ntri, nprims;     /* scene triangles; those kept */
    prim_ref *buf[2];
    lanes_pool pool;
    worker workers[MAX_THREADS];
    atomic_bool failed;

    /* phase 0 */
    size_t nblocks0;
    uint32_t *blk_valid;
    aabb *blk_geo, *blk_cent;
    int root_buf;

    /* phase 1 */
    tnode *cur, *next;
    size_t ncur, nnext, cap_cur, cap_next;
    tblock *blocks;
    size_t nblocks, cap_blocks;
    bin *blk_bins;
    size_t cap_blk_bins;
    int level_buf;            /* buffer holding the current level's ranges */
    lanes_bvh2_node *top;
    size_t ntop, cap_top;

    /* phase 2 */
    size_t worker_cap0;
    task *tasks;
    size_t ntasks, cap_tasks;
    uint64_t *order;          /* (UINT32_MAX - size) << 32 | task index */

    /* phase 3 */
    lanes_bvh2 *out;
} builder;

#define GROW(arr, cap, need) lanes_grow_array((void **)&(arr), &(cap), (need), sizeof(*(arr)))

/* ------------------------------------------------------------------------
 * Phase 0: references. */

static void refs_block(void *ctx, size_t blk, int tid)
{
    (void)tid;
    builder *B = ctx;
    size_t b = blk * BLOCK, e = b + BLOCK < B->ntri ? b + BLOCK : B->ntri;
    const float *v = B->scene->verts;
    prim_ref *out = B->buf[0];
    aabb geo, cent;
    aabb_empty(&geo);
    aabb_empty(&cent);
    uint32_t valid = 0;
    for (size_t i = b; i < e; i++) {
        const float *t = v + 9 * i;
        prim_ref *r = &out[i];
        bool ok = true;
        for (int k = 0; k < 9; k++) ok &= isfinite(t[k]) != 0;
        for (int a = 0; a < 3; a++) {
            r->lo[a] = fmin_(fmin_(t[a], t[3 + a]), t[6 + a]);
            r->hi[a] = fmax_(fmax_(t[a], t[3 + a]), t[6 + a]);
        }
        r->id = (uint32_t)i;
        r->valid = ok;
        if (ok) {
            float c[3];
            centroid2(r, c);
            aabb_grow(&geo, r->lo, r->hi);
            aabb_grow_point(&cent, c);
            valid++;
        }
    }
    B->blk_valid[blk] = valid;
    B->blk_geo[blk] = geo;
    B->blk_cent[blk] = cent;
}

/* blk_valid holds each block's output offset by now. */
static void compact_block(void *ctx, size_t blk, int tid)
{
    (void)tid;
    builder *B = ctx;
    size_t b = blk * BLOCK, e = b + BLOCK < B->ntri ? b + BLOCK : B->ntri;
    const prim_ref *in = B->buf[0];
    prim_ref *out = B->buf[1] + B->blk_valid[blk];
    for (size_t i = b; i < e; i++)
        if (in[i].valid) *out++ = in[i];
}

/* ------------------------------------------------------------------------
 * Phase 2: serial recursive build of one task. */

/* Node buffers start at an even share of the worst case (2 nodes per
 * reference) and double if a thread gets more than its share. */
static uint32_t worker_push(builder *B, worker *w, size_t n)
{
    if (w->count + n > w->cap) {
        size_t c = w->cap ? 2 * w->cap : B->worker_cap0;
        while (c < w->count + n) c *= 2;
        lanes_bvh2_node *p = lanes_big_alloc(c, sizeof *p);
        if (!p) {
            atomic_store(&B->failed, true);
            return UINT32_MAX;
        }
        if (w->count) memcpy(p, w->nodes, w->count * sizeof *p);
        free(w->nodes);
        w->nodes = p;
        w->cap = c;
    }
    uint32_t i = (uint32_t)w->count;
    w->count += n;
    return i;
}

/* Hoare partition; also collects the centroid bounds of both sides. The
 * split comes by value: a local copy cannot alias the references being
 * swapped, so its fields stay in registers. */
static uint32_t partition_inplace(prim_ref *r, uint32_t begin, uint32_t end, split s, aabb *lc,
                                  aabb *rc)
{
    uint32_t i = begin, j = end;
    aabb l = *lc, h = *rc;
    float c[3];
    for (;;) {
        while (i < j && goes_left(&s, &r[i])) {
            centroid2(&r[i], c);
            aabb_grow_point(&l, c);
            i++;
        }
        while (i < j && !goes_left(&s, &r[j - 1])) {
            centroid2(&r[j - 1], c);
            aabb_grow_point(&h, c);
            j--;
        }
        if (i >= j) break;
        prim_ref t = r[i];
        r[i] = r[j - 1];
        r[j - 1] = t;
        centroid2(&r[i], c);
        aabb_grow_point(&l, c);
        centroid2(&r[j - 1], c);
        aabb_grow_point(&h, c);
        i++;
        j--;
    }
    *lc = l;
    *rc = h;
    return i;
}

static void bounds_of(const prim_ref *r, uint32_t begin, uint32_t end, aabb *geo, aabb *cent)
{
    aabb_empty(geo);
    aabb_empty(cent);
    for (uint32_t i = begin; i < end; i++) {
        float c[3];
        centroid2(&r[i], c);
        aabb_grow(geo, r[i].lo, r[i].hi);
        aabb_grow_point(cent, c);
    }
}

/* Merges the geometry bounds of bins [from, to) of one axis. */
static void bins_bounds(const bin *b, int from, int to, aabb *out)
{
    aabb_empty(out);
    for (int k = from; k < to; k++) aabb_grow(out, b[k].lo, b[k].hi);
}

/* Leaf or split for a node of n references whose bins are filled. */
static bool prefer_leaf(const builder *B, uint32_t n, const aabb *geo, bool have, const split *s)
{
    if (n <= 1) return true;
    if ((int)n > B->maxleaf) return false;
    if (!have) return true;
    float A = half_area(geo);
    return B->ci * (float)sah_blocks(n, B->block) * A <= B->ct * A + B->ci * s->cost;
}

static void build_rec(builder *B, worker *w, prim_ref *r, uint32_t node, uint32_t begin,
                      uint32_t end, const aabb *geo, const aabb *cent, int level, task *t)
{
    uint32_t n = end - begin;
    if (level > t->depth) t->depth = level;
    binner bn;
    split s;
    memset(&s, 0, sizeof s);
    bool have = false;
    bool forced = level + ceil_log2(n) >= LANES_BVH_MAX_DEPTH;
    aabb lg, lc, rg, rc;
    bool pair = false; /* n == 2, split without bins; r[begin + swap] goes left */
    int swap = 0;
    if (n == 2 && !forced && binner_init(&bn, cent, B->bins)) {
        /* What binning would find, without the bins: pairs are the most
         * common node near the leaves. The two centroids fall in the first
         * and last bin of every usable axis, every axis offers the same
         * 1 | 1 split at the same cost (computed here in the same float
         * operations), and the first axis wins ties. (Doing the same for
         * up to 8 references, by trying each candidate bin or by sorting
         * them by bin, measured slower than the bins.) */
        const prim_ref *p = r + begin;
        int a = bn.ok[0] ? 0 : bn.ok[1] ? 1 : 2;
        swap = p[1].lo[a] + p[1].hi[a] < p[0].lo[a] + p[0].hi[a];
        memcpy(lg.lo, p[swap].lo, sizeof lg.lo);
        memcpy(lg.hi, p[swap].hi, sizeof lg.hi);
        memcpy(rg.lo, p[!swap].lo, sizeof rg.lo);
        memcpy(rg.hi, p[!swap].hi, sizeof rg.hi);
        s.cost = half_area(&lg) + half_area(&rg);
        have = pair = s.cost < INFINITY;
    } else if (n > 1 && !forced && binner_init(&bn, cent, B->bins)) {
        bin_refs(&bn, r + begin, n, w->bins);
        have = find_split(&bn, w->bins, B->block, &s);
        if (have) {
            const bin *ab = w->bins + s.axis * B->bins;
            bins_bounds(ab, 0, s.mid, &lg);
            bins_bounds(ab, s.mid, B->bins, &rg);
        }
    }
    if (prefer_leaf(B, n, geo, have, &s) || atomic_load_explicit(&B->failed, memory_order_relaxed)) {
        w->nodes[node].first = begin;
        w->nodes[node].count = n;
        t->sah += (double)B->ci * sah_blocks(n, B->block) * half_area_d(geo);
        return;
    }
    uint32_t mid;
    if (pair) {
        if (swap) {
            prim_ref t0 = r[begin];
            r[begin] = r[begin + 1];
            r[begin + 1] = t0;
        }
        mid = begin + 1;
        float c[3];
        centroid2(&r[begin], c);
        memcpy(lc.lo, c, sizeof c);
        memcpy(lc.hi, c, sizeof c);
        centroid2(&r[begin + 1], c);
        memcpy(rc.lo, c, sizeof c);
        memcpy(rc.hi, c, sizeof c);
    } else if (have) {
        aabb_empty(&lc);
        aabb_empty(&rc);
        mid = partition_inplace(r, begin, end, s, &lc, &rc);
    } else {
        mid = begin + n / 2;
        bounds_of(r, begin, mid, &lg, &lc);
        bounds_of(r, mid, end, &rg, &rc);
    }
    uint32_t c = worker_push(B, w, 2);
    if (c == UINT32_MAX) {
        w->nodes[node].first = begin;
        w->nodes[node].count = n;
        return;
    }
    lanes_bvh2_node *nd = w->nodes;
    nd[node].first = c;
    nd[node].count = 0;
    memcpy(nd[c].min, lg.lo, sizeof lg.lo);
    memcpy(nd[c].max, lg.hi, sizeof lg.hi);
    memcpy(nd[c + 1].min, rg.lo, sizeof rg.lo);
    memcpy(nd[c + 1].max, rg.hi, sizeof rg.hi);
    t->sah += (double)B->ct * half_area_d(geo);
    build_rec(B, w, r, c, begin, mid, &lg, &lc, level + 1, t);
    build_rec(B, w, r, c + 1, mid, end, &rg, &rc, level + 1, t);
}

/* Item 0 allocates the outputs whose size is known by now: the triangle
 * arrays are zeroed as they are allocated, a serial pass over 36 bytes per
 * triangle that costs less while the other threads build. */
static void run_task(void *ctx, size_t item, int tid)
{
    builder *B = ctx;
    if (item == 0) {
        lanes_bvh2 *bvh = B->out;
        bvh->prim_index = lanes_big_alloc_full(B->nprims, sizeof *bvh->prim_index);
        if (!bvh->prim_index || !lanes_triangles_alloc(&bvh->tris, B->nprims))
            atomic_store(&B->failed, true);
        return;
    }
    task *t = &B->tasks[(uint32_t)B->order[item - 1]];
    worker *w = &B->workers[tid];
    t->tid = tid;
    t->start = w->count;
    t->depth = t->level;
    t->sah = 0.0;
    uint32_t root = worker_push(B, w, 1);
    if (root == UINT32_MAX) {
        t->count = 0;
        return;
    }
    memcpy(w->nodes[root].min, t->geo.lo, sizeof t->geo.lo);
    memcpy(w->nodes[root].max, t->geo.hi, sizeof t->geo.hi);
    build_rec(B, w, B->buf[t->buf], root, t->begin, t->end, &t->geo, &t->cent, t->level, t);
    t->count = w->count - t->start;
}

/* ------------------------------------------------------------------------
 * Phase 1: the top levels, all threads on each level. */

static void top_bin_block(void *ctx, size_t i, int tid)
{
    (void)tid;
    builder *B = ctx;
    const tblock *blk = &B->blocks[i];
    const tnode *nd = &B->cur[blk->node];
    if (!nd->sah) return;
    bin *bins = B->blk_bins + i * 3 * (size_t)B->bins;
    bin_refs(&nd->bn, B->buf[B->level_buf] + blk->begin, blk->end - blk->begin, bins);
}

static void top_count_block(void *ctx, size_t i, int tid)
{
    (void)tid;
    builder *B = ctx;
    tblock *blk = &B->blocks[i];
    const tnode *nd = &B->cur[blk->node];
    const prim_ref *r = B->buf[B->level_buf];
    aabb_empty(&blk->lg);
    aabb_empty(&blk->lc);
    aabb_empty(&blk->rg);
    aabb_empty(&blk->rc);
    uint32_t nl = 0;
    uint32_t cut = nd->begin + nd->nleft; /* middle splits */
    for (uint32_t j = blk->begin; j < blk->end; j++) {
        bool left = nd->sah ? goes_left(&nd->s, &r[j]) : j < cut;
        float c[3];
        centroid2(&r[j], c);
        if (left) {
            aabb_grow(&blk->lg, r[j].lo, r[j].hi);
            aabb_grow_point(&blk->lc, c);
            nl++;
        } else {
            aabb_grow(&blk->rg, r[j].lo, r[j].hi);
            aabb_grow_point(&blk->rc, c);
        }
    }
    blk->nl = nl;
}

static void top_scatter_block(void *ctx, size_t i, int tid)
{
    (void)tid;
    builder *B = ctx;
    const tblock *blk = &B->blocks[i];
    const tnode *nd = &B->cur[blk->node];
    const prim_ref *r = B->buf[B->level_buf];
    prim_ref *o = B->buf[B->level_buf ^ 1];
    uint32_t l = blk->ldst, h = blk->rdst;
    uint32_t cut = nd->begin + nd->nleft;
    for (uint32_t j = blk->begin; j < blk->end; j++) {
        bool left = nd->sah ? goes_left(&nd->s, &r[j]) : j < cut;
        if (left)
            o[l++] = r[j];
        else
            o[h++] = r[j];
    }
}

static void set_bounds(lanes_bvh2_node *n, const aabb *b)
{
    memcpy(n->min, b->lo, sizeof b->lo);
    memcpy(n->max, b->hi, sizeof b->hi);
}

static bool add_task(builder *B, uint32_t begin, uint32_t end, uint32_t slot, int level, int buf,
                     const aabb *geo, const aabb *cent)
{
    if (!GROW(B->tasks, B->cap_tasks, B->ntasks + 1)) return false;
    task *t = &B->tasks[B->ntasks++];
    memset(t, 0, sizeof *t);
    t->begin = begin;
    t->end = end;
    t->slot = slot;
    t->level = level;
    t->buf = buf;
    t->geo = *geo;
    t->cent = *cent;
    return true;
}

/* A child of a phase-1 node: a task if small enough, else next level. */
static bool add_child(builder *B, uint32_t begin, uint32_t end, uint32_t slot, int level,
                      const aabb *geo, const aabb *cent)
{
    int buf = B->level_buf ^ 1;
    if (end - begin <= B->task_size) return add_task(B, begin, end, slot, level, buf, geo, cent);
    if (!GROW(B->next, B->cap_next, B->nnext + 1)) return false;
    tnode *n = &B->next[B->nnext++];
    memset(n, 0, sizeof *n);
    n->begin = begin;
    n->end = end;
    n->slot = slot;
    n->level = level;
    n->geo = *geo;
    n->cent = *cent;
    return true;
}

static bool top_level(builder *B)
{
    const size_t nb3 = 3 * (size_t)B->bins;
    /* blocks */
    B->nblocks = 0;
    for (size_t i = 0; i < B->ncur; i++) {
        tnode *nd = &B->cur[i];
        uint32_t n = nd->end - nd->begin;
        bool forced = nd->level + ceil_log2(n) >= LANES_BVH_MAX_DEPTH;
        nd->sah = !forced && binner_init(&nd->bn, &nd->cent, B->bins);
        nd->blk0 = B->nblocks;
        nd->nblk = (n + BLOCK - 1) / BLOCK;
        if (!GROW(B->blocks, B->cap_blocks, B->nblocks + nd->nblk)) return false;
        for (size_t k = 0; k < nd->nblk; k++) {
            tblock *b = &B->blocks[B->nblocks++];
            b->node = i;
            b->begin = nd->begin + (uint32_t)(k * BLOCK);
            b->end = b->begin + BLOCK < nd->end ? b->begin + BLOCK : nd->end;
        }
    }
    if (!GROW(B->blk_bins, B->cap_blk_bins, B->nblocks * nb3)) return false;

    lanes_pool_run(&B->pool, B->nblocks, top_bin_block, B);

    for (size_t i = 0; i < B->ncur; i++) {
        tnode *nd = &B->cur[i];
        if (nd->sah) {
            bin *acc = B->blk_bins + nd->blk0 * nb3;
            for (size_t k = 1; k < nd->nblk; k++) bins_merge(acc, acc + k * nb3, (int)nb3);
            nd->sah = find_split(&nd->bn, acc, B->block, &nd->s);
        }
        /* Larger than a leaf may be: always split. */
        nd->nleft = nd->sah ? 0 : (nd->end - nd->begin) / 2;
    }

    lanes_pool_run(&B->pool, B->nblocks, top_count_block, B);

    for (size_t i = 0; i < B->ncur; i++) {
        tnode *nd = &B->cur[i];
        uint32_t nl = 0;
        for (size_t k = 0; k < nd->nblk; k++) nl += B->blocks[nd->blk0 + k].nl;
        uint32_t l = nd->begin, h = nd->begin + nl;
        aabb lg, lc, rg, rc;
        aabb_empty(&lg);
        aabb_empty(&lc);
        aabb_empty(&rg);
        aabb_empty(&rc);
        for (size_t k = 0; k < nd->nblk; k++) {
            tblock *b = &B->blocks[nd->blk0 + k];
            b->ldst = l;
            b->rdst = h;
            l += b->nl;
            h += (b->end - b->begin) - b->nl;
            aabb_merge(&lg, &b->lg);
            aabb_merge(&lc, &b->lc);
            aabb_merge(&rg, &b->rg);
            aabb_merge(&rc, &b->rc);
        }
        nd->nleft = nl;
        /* Children: a pair of slots at the end of the top array. */
        if (!GROW(B->top, B->cap_top, B->ntop + 2)) return false;
        uint32_t c = (uint32_t)B->ntop;
        B->ntop += 2;
        B->top[nd->slot].first = c;
        B->top[nd->slot].count = 0;
        set_bounds(&B->top[c], &lg);
        set_bounds(&B->top[c + 1], &rg);
        if (!add_child(B, nd->begin, nd->begin + nl, c, nd->level + 1, &lg, &lc)) return false;
        if (!add_child(B, nd->begin + nl, nd->end, c + 1, nd->level + 1, &rg, &rc)) return false;
    }

    lanes_pool_run(&B->pool, B->nblocks, top_scatter_block, B);

    tnode *t = B->cur;
    B->cur = B->next;
    B->next = t;
    size_t c = B->cap_cur;
    B->cap_cur = B->cap_next;
    B->cap_next = c;
    B->ncur = B->nnext;
    B->nnext = 0;
    B->level_buf ^= 1;
    return true;
}

/* ------------------------------------------------------------------------
 * Phase 3: assembly. */

static void finish_task(void *ctx, size_t item, int tid)
{
    (void)tid;
    builder *B = ctx;
    const task *t = &B->tasks[item];
    lanes_bvh2 *bvh = B->out;
    const lanes_bvh2_node *src = B->workers[t->tid].nodes + t->start;
    lanes_bvh2_node *dst = bvh->nodes;
    /* Local node k (k >= 1) goes to offset + k - 1; node 0 to the slot. */
    for (size_t k = 0; k < t->count; k++) {
        lanes_bvh2_node n = src[k];
        if (n.count == 0) n.first = (uint32_t)(t->offset + (n.first - t->start) - 1);
        dst[k == 0 ? t->slot : t->offset + k - 1] = n;
    }
    const prim_ref *r = B->buf[t->buf];
    const float *v = B->scene->verts;
    lanes_triangles *tr = &bvh->tris;
    for (uint32_t j = t->begin; j < t->end; j++) {
        uint32_t id = r[j].id;
        const float *p = v + 9 * (size_t)id;
        bvh->prim_index[j] = id;
        tr->v0x[j] = p[0];
        tr->v0y[j] = p[1];
        tr->v0z[j] = p[2];
        tr->v1x[j] = p[3];
        tr->v1y[j] = p[4];
        tr->v1z[j] = p[5];
        tr->v2x[j] = p[6];
        tr->v2y[j] = p[7];
        tr->v2z[j] = p[8];
    }
}

/* Larger tasks first, so the last ones to finish are small; ties by index.
 * Only the schedule depends on this order, never the output. */
static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* ------------------------------------------------------------------------ */

void lanes_bvh_default_options(lanes_bvh_build_options *o)
{
    o->bins = 16;
    o->max_leaf_size = 4;
    o->sah_block = 1;
    o->traversal_cost = 1.0f;
    o->intersect_cost = 1.0f;
    o->threads = 0;
}

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void lanes_bvh2_free(lanes_bvh2 *bvh)
{
    if (!bvh) return;
    free(bvh->nodes);
    free(bvh->prim_index);
    lanes_triangles_free(&bvh->tris);
    memset(bvh, 0, sizeof *bvh);
}

static void builder_free(builder *B)
{
    free(B->buf[0]);
    free(B->buf[1]);
    free(B->blk_valid);
    free(B->blk_geo);
    free(B->blk_cent);
    free(B->cur);
    free(B->next);
    free(B->blocks);
    free(B->blk_bins);
    free(B->top);
    free(B->tasks);
    free(B->order);
    for (int i = 0; i < MAX_THREADS; i++) {
        free(B->workers[i].bins);
        free(B->workers[i].nodes);
    }
}

/* The builder's reasons are fixed texts; running out of memory is the one
 * that is not the input's fault. */
static lanes_status fail(lanes_error *err, const char *why)
{
    lanes_status status = strcmp(why, "out of memory") == 0 ? LANES_ERR_OUT_OF_MEMORY : LANES_ERR_BAD_INPUT;
    return lanes_error_set(err, status, "bvh build: %s", why);
}

lanes_status lanes_bvh2_build(const lanes_scene *scene, const lanes_bvh_build_options *opt, lanes_bvh2 *bvh,
                              lanes_error *err)
{
    double t0 = now_seconds();
    lanes_bvh_build_options defaults;
    if (!opt) {
        lanes_bvh_default_options(&defaults);
        opt = &defaults;
    }
    if (!bvh) return fail(err, "no output");
    memset(bvh, 0, sizeof *bvh);
    if (!scene) return fail(err, "no scene");
    if (opt->bins < 2 || opt->bins > MAX_BINS)
        return fail(err, "bins must be between 2 and 256");
    if (opt->max_leaf_size < 1) return fail(err, "max_leaf_size must be at least 1");
    if (opt->sah_block < 1 || opt->sah_block > 64) return fail(err, "sah_block must be between 1 and 64");
    if (!(opt->traversal_cost >= 0.0f && opt->traversal_cost <= FLT_MAX) ||
        !(opt->intersect_cost >= 0.0f && opt->intersect_cost <= FLT_MAX))
        return fail(err, "costs must be finite and not negative");
    if (opt->threads < 0) return fail(err, "threads must be 0 (all cores) or more");
    if (scene->triangle_count == 0 || !scene->verts) return fail(err, "the scene has no triangles");
    /* Node indices are 32-bit and a tree has up to 2N - 1 nodes. */
    if (scene->triangle_count > (size_t)INT32_MAX)
        return fail(err, "too many triangles (at most 2^31 - 1)");

    builder *B = calloc(1, sizeof *B);
    if (!B) return fail(err, "out of memory");
    B->scene = scene;
    B->bins = opt->bins;
    B->maxleaf = opt->max_leaf_size;
    B->block = (uint32_t)opt->sah_block;
    B->ct = opt->traversal_cost;
    B->ci = opt->intersect_cost;
    B->ntri = scene->triangle_count;
    atomic_init(&B->failed, false);
    B->out = bvh;
    int threads = lanes_parallel_threads(opt->threads);
    bool ok = false;
    const char *why = "out of memory";

    B->nblocks0 = (B->ntri + BLOCK - 1) / BLOCK;
    B->buf[0] = lanes_big_alloc_full(B->ntri, sizeof(prim_ref));
    B->blk_valid = malloc(B->nblocks0 * sizeof *B->blk_valid);
    B->blk_geo = malloc(B->nblocks0 * sizeof *B->blk_geo);
    B->blk_cent = malloc(B->nblocks0 * sizeof *B->blk_cent);
    if (!B->buf[0] || !B->blk_valid || !B->blk_geo || !B->blk_cent) {
        builder_free(B);
        free(B);
        return fail(err, why);
    }
    lanes_pool_start(&B->pool, threads, NULL, 0);
    for (int i = 0; i < B->pool.threads; i++) {
        B->workers[i].bins = malloc(3 * (size_t)B->bins * sizeof(bin));
        if (!B->workers[i].bins) goto done;
    }

    /* Phase 0. */
    lanes_pool_run(&B->pool, B->nblocks0, refs_block, B);
    size_t n = 0;
    aabb geo, cent;
    aabb_empty(&geo);
    aabb_empty(&cent);
    for (size_t i = 0; i < B->nblocks0; i++) {
        uint32_t c = B->blk_valid[i];
        B->blk_valid[i] = (uint32_t)n;
        n += c;
        aabb_merge(&geo, &B->blk_geo[i]);
        aabb_merge(&cent, &B->blk_cent[i]);
    }
    bvh->skipped = B->ntri - n;
    if (n == 0) {
        why = "no triangle has finite coordinates";
        goto done;
    }
    B->task_size = (uint32_t)(n / TASK_DIV > TASK_MIN ? n / TASK_DIV : TASK_MIN);
    if (B->task_size < (uint32_t)B->maxleaf) B->task_size = (uint32_t)B->maxleaf;
    bool need_second = n > B->task_size;
    if (need_second || n < B->ntri) {
        /* only [0, n) is written: the refs of the triangles kept */
        B->buf[1] = lanes_big_alloc(B->ntri, sizeof(prim_ref));
        if (!B->buf[1]) goto done;
        lanes_prefault(B->buf[1], n * sizeof(prim_ref));
    }
    B->root_buf = 0;
    if (n < B->ntri) {
        lanes_pool_run(&B->pool, B->nblocks0, compact_block, B);
        B->root_buf = 1;
    }

    /* Phase 1. */
    if (!GROW(B->top, B->cap_top, 1)) goto done;
    B->ntop = 1;
    set_bounds(&B->top[0], &geo);
    B->top[0].first = 0;
    B->top[0].count = 0;
    B->level_buf = B->root_buf;
    if (n <= B->task_size) {
        if (!add_task(B, 0, (uint32_t)n, 0, 1, B->root_buf, &geo, &cent)) goto done;
    } else {
        if (!GROW(B->cur, B->cap_cur, 1)) goto done;
        memset(&B->cur[0], 0, sizeof B->cur[0]);
        B->cur[0].begin = 0;
        B->cur[0].end = (uint32_t)n;
        B->cur[0].slot = 0;
        B->cur[0].level = 1;
        B->cur[0].geo = geo;
        B->cur[0].cent = cent;
        B->ncur = 1;
        while (B->ncur > 0)
            if (!top_level(B)) goto done;
    }

    /* Phase 2. */
    B->worker_cap0 = 2 * n / (size_t)B->pool.threads + 4096;
    B->order = malloc(B->ntasks * sizeof *B->order);
    if (!B->order) goto done;
    for (size_t i = 0; i < B->ntasks; i++)
        B->order[i] = (uint64_t)(UINT32_MAX - (B->tasks[i].end - B->tasks[i].begin)) << 32 | i;
    qsort(B->order, B->ntasks, sizeof *B->order, cmp_u64);
    B->nprims = n;
    lanes_pool_run(&B->pool, B->ntasks + 1, run_task, B);
    if (atomic_load(&B->failed)) goto done;

    /* Phase 3. */
    size_t total = B->ntop;
    int depth = 1;
    double sah = 0.0;
    for (size_t i = 0; i < B->ntasks; i++) {
        task *t = &B->tasks[i];
        t->offset = total;
        total += t->count - 1;
        if (t->depth > depth) depth = t->depth;
    }
    bvh->nodes = lanes_big_alloc_full(total, sizeof *bvh->nodes);
    if (!bvh->nodes) goto done;
    memcpy(bvh->nodes, B->top, B->ntop * sizeof *B->top);
    lanes_pool_run(&B->pool, B->ntasks, finish_task, B);

    /* The top nodes are all interior except task roots, which the tasks
     * count; sums in task order keep the result independent of threads. */
    {
        bool *is_task_root = calloc(B->ntop, sizeof *is_task_root);
        if (!is_task_root) goto done;
        for (size_t i = 0; i < B->ntasks; i++) is_task_root[B->tasks[i].slot] = true;
        for (size_t i = 0; i < B->ntop; i++) {
            if (is_task_root[i]) continue;
            aabb b;
            memcpy(b.lo, B->top[i].min, sizeof b.lo);
            memcpy(b.hi, B->top[i].max, sizeof b.hi);
            sah += (double)B->ct * half_area_d(&b);
        }
        free(is_task_root);
    }
    for (size_t i = 0; i < B->ntasks; i++) sah += B->tasks[i].sah;
    double root_area = half_area_d(&geo);
    bvh->node_count = total;
    bvh->prim_count = n;
    bvh->sah_cost = root_area > 0.0 ? sah / root_area : 0.0;
    bvh->depth = depth;
    bvh->traversal_cost = B->ct;
    bvh->intersect_cost = B->ci;
    bvh->sah_block = (int)B->block;
    bvh->threads = B->pool.threads;
    ok = true;

done:
    lanes_pool_stop(&B->pool);
    builder_free(B);
    free(B);
    if (!ok) {
        size_t skipped = bvh->skipped;
        lanes_bvh2_free(bvh);
        bvh->skipped = skipped;
        return fail(err, why);
    }
    bvh->build_seconds = now_seconds() - t0;
    return LANES_OK;
}
