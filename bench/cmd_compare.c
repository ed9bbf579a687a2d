/* `lanes compare`: lanes' single-ray traversals against Embree's query APIs,
 * on the same rays, the same triangles and the same threads.
 *
 * Every figure is a ratio from one run (design.md, "Measuring"): the rays
 * are generated once, laid out for each engine and API before the clock
 * starts, and each configuration is timed as the median of --reps runs of
 * its trace calls alone. Threads take fixed-size chunks of the same ray
 * array from a shared counter, for both engines alike, each thread pinned
 * to one CPU and running with FTZ/DAZ set (Embree's requirement, applied
 * to lanes too so the two see the same floating-point environment). */
#define _GNU_SOURCE /* pthread_setaffinity_np, CPU_SET */
#include "bench/cmd_compare.h"

#include <math.h>
#include <pthread.h>
#include <sched.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <embree3/rtcore_config.h>

#include "bench/cli_common.h"
#include "bench/embree_adapter.h"
#include "bench/hits_judge.h"
#include "bench/ray_sets.h"
#include "build/bvh.h"
#include "build/parallel.h"
#include "build/scene.h"
#include "build/scene_load.h"
#include "simd/isa.h"
#include "trace/kernels.h"
#include "trace/render.h"

enum {
    MAX_THREADS = 256,
    /* Work item of the threads: large enough that fetching it costs
     * nothing, small enough to balance; a multiple of every packet width. */
    CHUNK = 4096,
};

typedef enum { KIND_PRIMARY, KIND_SHADOW, KIND_DIFFUSE, KIND_SHUFFLED, KIND_COUNT } ray_kind;
static const char *const kind_names[KIND_COUNT] = {"primary", "shadow", "diffuse",
                                                   "diffuse-shuffled"};

/* ---- threads ------------------------------------------------------------ */

/* Work on rays [begin, end) of a run. */
typedef void (*work_fn)(void *ctx, size_t begin, size_t end);

/* Persistent pinned pools (build/parallel.h): creating threads per
 * repetition would time thread start-up, and an unpinned thread may
 * migrate mid-run. Items are CHUNKs of rays. */
typedef struct {
    work_fn fn;
    void *ctx;
    size_t n;
} chunked_run;

static void chunk_task(void *p, size_t item, int worker)
{
    chunked_run *r = p;
    (void)worker;
    size_t b = item * CHUNK, e = b + CHUNK < r->n ? b + CHUNK : r->n;
    unsigned csr = lanes_fp_fast_enter();
    r->fn(r->ctx, b, e);
    lanes_fp_restore(csr);
}

/* Seconds from the moment the workers are released to the moment the last
 * item is done. */
static double pool_run(lanes_pool *p, work_fn fn, void *ctx, size_t n)
{
    chunked_run r = {fn, ctx, n};
    uint64_t t0 = cli_now_ns();
    lanes_pool_run(p, (n + CHUNK - 1) / CHUNK, chunk_task, &r);
    return (double)(cli_now_ns() - t0) * 1e-9;
}

/* ---- the two engines as work functions --------------------------------- */

typedef struct {
    const lanes_kernels *k;
    lanes_scheme scheme;
    const lanes_bvh2 *bvh2;
    const lanes_wbvh *wide;
    lanes_accuracy accuracy;
    const lanes_ray *rays; /* prepared with the accuracy mode's reciprocals */
    lanes_hit *hits;
    uint8_t *occluded;
    bool occlusion;
    /* packets: the rays laid out as SoA before timing, in packets of
     * LANES_PACKET_MAX_RAYS consecutive rays; their t range is restored
     * from tnear0/tfar0 before each run (traversal shrinks tfar) */
    bool packet;
    bool hybrid; /* packets of the set's width through the wide BVH */
    bool stream; /* octant-sorted groups of rays through the wide BVH */
    lanes_rays soa;
    float *tnear0, *tfar0, *u, *v;
    uint32_t *prim;
    lanes_trace_stats *stats; /* the counted run (--stats); NULL when timed */
} lanes_job;

/* Packets of consecutive rays: CHUNK is a multiple of the packet size, so a
 * worker's range starts on a packet boundary. */
static void packet_work(const lanes_job *j, size_t b, size_t e)
{
    for (size_t p = b; p < e; p += LANES_PACKET_MAX_RAYS) {
        size_t n = e - p < LANES_PACKET_MAX_RAYS ? e - p : LANES_PACKET_MAX_RAYS;
        lanes_rays view = lanes_rays_view(&j->soa, p, n);
        lanes_frustum f;
        j->k->frustum_build(&view, NULL, n, &f);
        lanes_packet_options po = {LANES_PACKET_PARTITION, j->accuracy, &f, true, false, j->occlusion};
        j->k->trace_packet(j->bvh2, &po, &view, j->prim + p, j->u + p, j->v + p,
                           j->occluded ? j->occluded + p : NULL, NULL);
    }
}

static bool packet_setup(lanes_job *j, size_t n)
{
    size_t nn = n ? n : 1;
    if (!lanes_rays_alloc(&j->soa, nn)) return false;
    j->tnear0 = malloc(nn * sizeof(float));
    j->tfar0 = malloc(nn * sizeof(float));
    j->u = malloc((nn + LANES_MAX_W) * sizeof(float));
    j->v = malloc((nn + LANES_MAX_W) * sizeof(float));
    j->prim = malloc((nn + LANES_MAX_W) * sizeof(uint32_t));
    if (!j->tnear0 || !j->tfar0 || !j->u || !j->v || !j->prim) return false;
    for (size_t i = 0; i < n; i++) {
        const lanes_ray *r = &j->rays[i];
        j->soa.ox[i] = r->o[0], j->soa.oy[i] = r->o[1], j->soa.oz[i] = r->o[2];
        j->soa.dx[i] = r->d[0], j->soa.dy[i] = r->d[1], j->soa.dz[i] = r->d[2];
        j->soa.tnear[i] = r->tnear, j->soa.tfar[i] = r->tfar;
    }
    j->soa.count = n;
    j->k->rays_prepare(&j->soa, lanes_accuracy_precision(j->accuracy).rcp);
    memcpy(j->tnear0, j->soa.tnear, n * sizeof(float));
    memcpy(j->tfar0, j->soa.tfar, n * sizeof(float));
    return true;
}

static void packet_reset(lanes_job *j, size_t n)
{
    memcpy(j->soa.tnear, j->tnear0, n * sizeof(float));
    memcpy(j->soa.tfar, j->tfar0, n * sizeof(float));
    for (size_t i = 0; i < n; i++) j->prim[i] = LANES_NO_HIT;
    if (j->occluded) memset(j->occluded, 0, n);
}

static void packet_results(lanes_job *j, size_t n)
{
    if (j->occlusion) return;
    for (size_t i = 0; i < n; i++)
        j->hits[i] = j->prim[i] == LANES_NO_HIT ? (lanes_hit){INFINITY, 0.0f, 0.0f, LANES_NO_HIT}
                                                : (lanes_hit){j->soa.tfar[i], j->u[i], j->v[i], j->prim[i]};
}

static void packet_free(lanes_job *j)
{
    if (!j->packet) return;
    lanes_rays_free(&j->soa);
    free(j->tnear0), free(j->tfar0), free(j->u), free(j->v), free(j->prim);
}

static void lanes_work(void *ctx, size_t b, size_t e)
{
    const lanes_job *j = ctx;
    if (j->packet) {
        packet_work(j, b, e);
        return;
    }
    if (j->stream) {
        if (j->occlusion)
            j->k->occluded_stream(j->wide, j->accuracy, j->rays + b, e - b, j->occluded + b, j->stats);
        else
            j->k->trace_stream(j->wide, j->accuracy, j->rays + b, e - b, j->hits + b, j->stats);
        return;
    }
    if (j->hybrid) {
        if (j->occlusion)
            j->k->occluded_hybrid(j->wide, j->accuracy, j->rays + b, e - b, j->occluded + b, j->stats);
        else
            j->k->trace_hybrid(j->wide, j->accuracy, j->rays + b, e - b, j->hits + b, j->stats);
        return;
    }
    if (j->occlusion) {
        if (j->scheme == LANES_SCHEME_WIDE)
            j->k->occluded_wide(j->wide, j->accuracy, j->rays + b, e - b,
                                j->occluded + b, j->stats);
        else
            j->k->occluded_bvh2(j->bvh2, j->accuracy, j->rays + b, e - b, j->occluded + b, j->stats);
    } else {
        if (j->scheme == LANES_SCHEME_WIDE)
            j->k->trace_wide(j->wide, j->accuracy, j->rays + b, e - b, j->hits + b, j->stats);
        else
            j->k->trace_bvh2(j->bvh2, j->accuracy, j->rays + b, e - b, j->hits + b, j->stats);
    }
}

typedef struct {
    const lanes_embree *e;
    lanes_embree_batch *batch;
    bool coherent;
} embree_job;

static void embree_work(void *ctx, size_t b, size_t e)
{
    embree_job *j = ctx;
    lanes_embree_batch_trace(j->e, j->batch, b, e, j->coherent);
}

/* ---- results ------------------------------------------------------------ */

typedef struct {
    ray_kind kind;
    bool embree;
    char method[40];
    char isa[16];
    int threads;
    double mrays;
    double ratio; /* against the best Embree row of the same kind and threads */
    /* --stats, lanes rows but packet: per ray, from one counted run */
    bool counted;
    double nodes, leaves, triangles, node_util, leaf_util;
} row;

typedef struct {
    lanes_isa isa;
    ray_kind kind;
    size_t rays, agree;
    hits_verdicts differ; /* the others, judged by the exact reference */
} agreement;

typedef struct {
    row *rows;
    size_t count, cap;
    agreement agree[LANES_ISA_COUNT * KIND_COUNT];
    size_t agree_count;
} results;

static row *add_row(results *r)
{
    if (r->count == r->cap) {
        size_t cap = r->cap ? 2 * r->cap : 64;
        row *p = realloc(r->rows, cap * sizeof *p);
        if (!p) cli_fail("compare: out of memory");
        r->rows = p;
        r->cap = cap;
    }
    row *w = &r->rows[r->count++];
    memset(w, 0, sizeof *w);
    return w;
}

/* ---- the command -------------------------------------------------------- */

typedef struct {
    const char *scene_spec;
    const char *csv;
    bool json, quick;
    bool stats;        /* traversal counters per ray, from one more (untimed) run */
    int threads;       /* all-threads figure; 1 means single thread only */
    long rays;         /* camera rays, approximately */
    int reps;
    lanes_embree_isa embree_isa;
    bool isa_given;
    lanes_isa isa;
    lanes_accuracy accuracy; /* of every lanes configuration */
    double scale, translate; /* the scene moved: p' = scale p + translate */
    int node_width;          /* 0: each set's own */
} options;

typedef struct {
    options opt;
    lanes_scene scene;
    lanes_bvh2 bvh2;
    lanes_wbvh wide[3]; /* widths 4, 8, 16 */
    lanes_embree *embree;
    hits_judge judge; /* over bvh2 */
    lanes_isa isas[LANES_ISA_COUNT];
    int isa_count;
    lanes_isa ref_isa; /* traces the primary rays the secondary ones start from */
    lanes_pool pools[2]; /* single thread, all threads */
    int pool_count;
    results res;
    int width, height;
    size_t ray_count[KIND_COUNT];
} compare;

static int width_slot(int w) { return w == 4 ? 0 : w == 8 ? 1 : 2; }

/* A measured set's kernels, for the node width asked for. */
static const lanes_kernels *set_kernels(const compare *c, lanes_isa isa)
{
    return c->opt.node_width ? lanes_kernels_for_width(isa, c->opt.node_width) : lanes_kernels_for(isa);
}

/* On stderr, so that stdout holds only the table (or the JSON). */
static void progress(const compare *c, const char *fmt, ...) CLI_PRINTF(2, 3);
static void progress(const compare *c, const char *fmt, ...)
{
    va_list ap;
    if (c->opt.json) return;
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fflush(stderr);
}

/* One measured configuration: an engine, its method and set, its own
 * output arrays. */
typedef struct {
    bool embree;
    lanes_job lj;
    embree_job ej;
    lanes_embree_method method;
    char name[40], isa[16];
    double seconds[2][64]; /* per pool, per repetition */
} config;

/* A lanes configuration of job j, named name, with output arrays for n
 * rays (occlusion flags padded by pad bytes). */
static config *add_lanes_config(config *cf, lanes_job j, const char *name, size_t n, size_t pad)
{
    cf->lj = j;
    if (j.occlusion)
        cf->lj.occluded = malloc(n + pad);
    else
        cf->lj.hits = malloc(n * sizeof *cf->lj.hits);
    if (!cf->lj.occluded && !cf->lj.hits) cli_fail("compare: out of memory");
    snprintf(cf->name, sizeof cf->name, "%s", name);
    snprintf(cf->isa, sizeof cf->isa, "%s", j.k->name);
    return cf;
}

/* The traversal counters of a lanes configuration over the same rays in
 * the same chunks as a timed run, on this thread: the counting copies of
 * the kernels, so never timed. */
static void count_config(const config *cf, size_t n, lanes_trace_stats *out)
{
    lanes_job j = cf->lj;
    memset(out, 0, sizeof *out);
    j.stats = out;
    unsigned csr = lanes_fp_fast_enter();
    for (size_t b = 0; b < n; b += CHUNK) lanes_work(&j, b, b + CHUNK < n ? b + CHUNK : n);
    lanes_fp_restore(csr);
}

static double per(uint64_t a, uint64_t b) { return b ? (double)a / (double)b : 0.0; }

/* --stats counts lanes' configurations but packets, whose counters count
 * rays per lane, not children and triangles (lanes study reports theirs). */
static bool countable(const config *cf) { return !cf->embree && !cf->lj.packet; }

static void run_config(lanes_pool *p, config *cf, size_t n, double *seconds)
{
    double s;
    if (cf->embree) {
        lanes_embree_batch_reset(cf->ej.batch); /* outside the clock */
        s = pool_run(p, embree_work, &cf->ej, n);
    } else {
        if (cf->lj.packet) packet_reset(&cf->lj, n); /* outside the clock */
        s = pool_run(p, lanes_work, &cf->lj, n);
        if (cf->lj.packet) packet_results(&cf->lj, n);
    }
    if (seconds) *seconds = s;
}

/* Every configuration of one kind of rays. The repetitions are interleaved
 * (one run of each configuration, then the next round) so that a change in
 * the machine's load during the measurement falls on all of them alike;
 * a warm-up round comes first and is not timed. */
static void run_kind(compare *c, ray_kind kind, const lanes_ray *rays, size_t n)
{
    bool occl = kind == KIND_SHADOW;
    size_t nn = n ? n : 1;
    config *cfg = calloc(LANES_ISA_COUNT * (LANES_SCHEME_COUNT + 3) + 2 * LANES_EMBREE_METHOD_COUNT,
                         sizeof *cfg);
    lanes_embree_batch batches[LANES_EMBREE_METHOD_COUNT];
    bool have_batch[LANES_EMBREE_METHOD_COUNT] = {false};
    /* lanes' copy of the rays, with the reciprocals of its accuracy mode */
    lanes_ray *mode_rays = malloc(nn * sizeof *mode_rays);
    if (!cfg || !mode_rays) cli_fail("compare: out of memory");
    for (size_t i = 0; i < n; i++) {
        mode_rays[i] = rays[i];
        lanes_ray_prepare_rcp(&mode_rays[i], lanes_accuracy_precision(c->opt.accuracy).rcp);
    }
    int ncfg = 0;
    c->ray_count[kind] = n;

    for (int ii = 0; ii < c->isa_count; ii++) {
        const lanes_kernels *k = set_kernels(c, c->isas[ii]);
        const lanes_job base = {.k = k, .bvh2 = &c->bvh2, .wide = &c->wide[width_slot(k->wide_width)],
                                .rays = mode_rays, .accuracy = c->opt.accuracy, .occlusion = occl};
        for (int sc = 0; sc < LANES_SCHEME_COUNT; sc++) {
            lanes_job j = base;
            j.scheme = (lanes_scheme)sc;
            add_lanes_config(&cfg[ncfg++], j, lanes_scheme_name((lanes_scheme)sc), nn, 0);
        }
        /* hybrid packets: LANES_W consecutive rays (a 2x2, 2x4 or 4x4
         * pixel block of a tile for camera rays) through the wide BVH */
        lanes_job hj = base;
        hj.scheme = LANES_SCHEME_WIDE;
        hj.hybrid = true;
        add_lanes_config(&cfg[ncfg++], hj, "hybrid", nn, 0);
        /* one stream per worker's chunk, sorted by octant inside the call */
        lanes_job sj = base;
        sj.scheme = LANES_SCHEME_WIDE;
        sj.stream = true;
        add_lanes_config(&cfg[ncfg++], sj, "stream", nn, 0);
        /* packets of 1024 consecutive rays (camera rays come in 8x8 pixel
         * tiles, so a packet is a strip of 16 tiles), partition traversal
         * of the BVH2 with the packet frustum built inside the clock */
        lanes_job pj = base;
        pj.scheme = LANES_SCHEME_SINGLE;
        pj.wide = NULL;
        pj.packet = true;
        config *cf = add_lanes_config(&cfg[ncfg++], pj, "packet", nn, LANES_MAX_W);
        if (!packet_setup(&cf->lj, n)) cli_fail("compare: out of memory");
    }
    for (int m = 0; m < LANES_EMBREE_METHOD_COUNT; m++) {
        if (!lanes_embree_supports(c->embree, (lanes_embree_method)m)) continue;
        lanes_error err;
        if (lanes_embree_batch_init(&batches[m], (lanes_embree_method)m, occl, rays, n, &err) != LANES_OK)
            cli_fail("compare: %s", err.message);
        have_batch[m] = true;
        for (int coherent = 0; coherent < 2; coherent++) {
            /* a single ray has no coherence to exploit: one context only */
            if (coherent && m == LANES_EMBREE_1) continue;
            config *cf = &cfg[ncfg++];
            cf->embree = true;
            cf->method = (lanes_embree_method)m;
            cf->ej = (embree_job){c->embree, &batches[m], coherent != 0};
            snprintf(cf->name, sizeof cf->name, "%s%s",
                     lanes_embree_method_name((lanes_embree_method)m, occl),
                     coherent ? "+coherent" : "");
            snprintf(cf->isa, sizeof cf->isa, "%s",
                     lanes_embree_isa_name(lanes_embree_get_isa(c->embree)));
        }
    }

    progress(c, "  %s: %zu rays, %d configurations x %d thread counts x %d rounds\n",
             kind_names[kind], n, ncfg, c->pool_count, c->opt.reps + 1);
    for (int round = -1; round < c->opt.reps; round++)
        for (int pi = 0; pi < c->pool_count; pi++)
            for (int i = 0; i < ncfg; i++)
                run_config(&c->pools[pi], &cfg[i], n, round < 0 ? NULL : &cfg[i].seconds[pi][round]);
    if (lanes_embree_error(c->embree)[0]) cli_fail("compare: %s", lanes_embree_error(c->embree));
    lanes_trace_stats *counts = NULL;
    if (c->opt.stats) {
        counts = calloc((size_t)ncfg, sizeof *counts);
        if (!counts) cli_fail("compare: out of memory");
        for (int i = 0; i < ncfg; i++)
            if (countable(&cfg[i])) count_config(&cfg[i], n, &counts[i]);
    }

    /* rows: per thread count, lanes then Embree; ratios against the best
     * Embree row of the same rays and threads */
    for (int pi = 0; pi < c->pool_count; pi++) {
        size_t first = c->res.count;
        double best = 0.0;
        for (int i = 0; i < ncfg; i++) {
            double s = cli_median(cfg[i].seconds[pi], (size_t)c->opt.reps);
            row *w = add_row(&c->res);
            w->kind = kind;
            w->embree = cfg[i].embree;
            snprintf(w->method, sizeof w->method, "%s", cfg[i].name);
            snprintf(w->isa, sizeof w->isa, "%s", cfg[i].isa);
            w->threads = c->pools[pi].threads;
            w->mrays = s > 0 ? (double)n / s * 1e-6 : 0.0;
            if (w->embree && w->mrays > best) best = w->mrays;
            w->counted = counts && countable(&cfg[i]);
            if (w->counted) {
                const lanes_trace_stats *t = &counts[i];
                w->nodes = per(t->nodes_visited, t->rays);
                w->leaves = per(t->leaves_visited, t->rays);
                w->triangles = per(t->triangles_tested, t->rays);
                w->node_util = per(t->node_lanes.active_lanes, t->node_lanes.lane_slots);
                w->leaf_util = per(t->leaf_lanes.active_lanes, t->leaf_lanes.lane_slots);
            }
        }
        for (size_t i = first; i < c->res.count; i++)
            c->res.rows[i].ratio = best > 0 ? c->res.rows[i].mrays / best : 0.0;
    }

    /* agreement: each set's wide scheme against rtcIntersect1/rtcOccluded1,
     * each difference judged */
    judge_cache jc;
    if (!judge_cache_init(&jc, rays, n)) cli_fail("compare: out of memory");
    lanes_hit *ref_hits = occl ? NULL : malloc(nn * sizeof *ref_hits);
    uint8_t *ref_occ = occl ? malloc(nn) : NULL;
    if (!ref_hits && !ref_occ) cli_fail("compare: out of memory");
    if (occl)
        lanes_embree_batch_occluded(&batches[LANES_EMBREE_1], ref_occ);
    else
        lanes_embree_batch_hits(&batches[LANES_EMBREE_1], ref_hits);
    for (int i = 0; i < ncfg; i++) {
        if (cfg[i].embree || cfg[i].lj.packet || cfg[i].lj.hybrid || cfg[i].lj.stream ||
            cfg[i].lj.scheme != LANES_SCHEME_WIDE)
            continue;
        agreement *a = &c->res.agree[c->res.agree_count++];
        a->isa = cfg[i].lj.k->isa;
        a->kind = kind;
        a->rays = n;
        a->agree = 0;
        memset(&a->differ, 0, sizeof a->differ);
        for (size_t r = 0; r < n; r++) {
            bool ok = occl ? (cfg[i].lj.occluded[r] != 0) == (ref_occ[r] != 0)
                           : hits_same(&cfg[i].lj.hits[r], &ref_hits[r]);
            if (ok) {
                a->agree++;
                continue;
            }
            judge_answer la = {.test = judge_test_of(c->opt.accuracy), .occlusion = occl},
                         ea = {.test = JUDGE_MOLLER, .occlusion = occl};
            if (occl) {
                la.occluded = cfg[i].lj.occluded[r] != 0;
                ea.occluded = ref_occ[r] != 0;
            } else {
                la.prim = cfg[i].lj.hits[r].prim, la.t = cfg[i].lj.hits[r].t;
                ea.prim = ref_hits[r].prim, ea.t = ref_hits[r].t;
            }
            hits_judge_pair(&c->judge, &jc, r, &la, &ea, &a->differ);
        }
    }
    judge_cache_free(&jc);
    free(ref_hits);
    free(ref_occ);
    for (int i = 0; i < ncfg; i++) {
        free(cfg[i].lj.hits);
        free(cfg[i].lj.occluded);
        packet_free(&cfg[i].lj);
    }
    for (int m = 0; m < LANES_EMBREE_METHOD_COUNT; m++)
        if (have_batch[m]) lanes_embree_batch_free(&batches[m]);
    free(counts);
    free(cfg);
    free(mode_rays);
}

static void print_table(FILE *out, const compare *c)
{
    fprintf(out, "%-17s %-7s %-24s %-10s %7s %10s %9s\n", "rays", "engine", "method", "isa",
            "threads", "Mrays/s", "vs Embree");
    for (size_t i = 0; i < c->res.count; i++) {
        const row *w = &c->res.rows[i];
        fprintf(out, "%-17s %-7s %-24s %-10s %7d %10.2f %9.2f\n", kind_names[w->kind],
                w->embree ? "embree" : "lanes", w->method, w->isa, w->threads, w->mrays, w->ratio);
    }
}

static void print_counts(FILE *out, const compare *c)
{
    fprintf(out, "\ntraversal per ray (lanes, one counted run of the same rays: node and leaf visits, a\n"
                 "packet's or group's visit once; triangles tested; utilisation: lanes holding a\n"
                 "real child or triangle over lane slots of the node and triangle tests):\n");
    fprintf(out, "%-17s %-24s %-10s %8s %8s %10s %10s %10s\n", "rays", "method", "isa", "nodes", "leaves",
            "triangles", "node util", "leaf util");
    for (size_t i = 0; i < c->res.count; i++) {
        const row *w = &c->res.rows[i];
        if (!w->counted || w->threads != 1) continue; /* the same counts on every pool's row */
        fprintf(out, "%-17s %-24s %-10s %8.2f %8.2f %10.2f %10.3f %10.3f\n", kind_names[w->kind], w->method,
                w->isa, w->nodes, w->leaves, w->triangles, w->node_util, w->leaf_util);
    }
}

static void write_csv(FILE *f, const char *path, const compare *c)
{
    fprintf(f, "rays,engine,method,isa,threads,mrays,ratio\n");
    for (size_t i = 0; i < c->res.count; i++) {
        const row *w = &c->res.rows[i];
        cli_csv_field(f, kind_names[w->kind]);
        fprintf(f, ",%s,", w->embree ? "embree" : "lanes");
        cli_csv_field(f, w->method);
        fputc(',', f);
        cli_csv_field(f, w->isa);
        fprintf(f, ",%d,%.4f,%.4f\n", w->threads, w->mrays, w->ratio);
    }
    cli_finish_file("compare: --csv", path, f);
}

static void print_json(const compare *c, double embree_build)
{
    printf("{\n  \"scene\": ");
    cli_json_string(stdout, c->scene.name[0] ? c->scene.name : c->opt.scene_spec);
    printf(",\n  \"triangles\": %zu,\n  \"cpu\": ", c->scene.triangle_count);
    cli_json_string(stdout, cli_cpu_description());
    printf(",\n  \"compiler\": ");
    cli_json_string(stdout, cli_compiler());
    printf(",\n  \"embree_version\": ");
    cli_json_string(stdout, RTC_VERSION_STRING);
    printf(",\n  \"embree_isa\": ");
    cli_json_string(stdout, lanes_embree_isa_name(lanes_embree_get_isa(c->embree)));
    printf(",\n  \"accuracy\": \"%s\"", lanes_accuracy_name(c->opt.accuracy));
    printf(",\n  \"scale\": ");
    cli_json_number(stdout, c->opt.scale);
    printf(",\n  \"translate\": ");
    cli_json_number(stdout, c->opt.translate);
    printf(",\n  \"image\": [%d, %d],\n  \"reps\": %d,\n", c->width, c->height, c->opt.reps);
    printf("  \"ray_counts\": {");
    for (int k = 0; k < KIND_COUNT; k++)
        printf("%s\"%s\": %zu", k ? ", " : "", kind_names[k], c->ray_count[k]);
    printf("},\n  \"build_seconds\": {\"lanes_bvh2\": %.6f", c->bvh2.build_seconds);
    for (int s = 0; s < 3; s++)
        if (c->wide[s].width)
            printf(", \"lanes_wide_%d\": %.6f", c->wide[s].width, c->wide[s].build_seconds);
    printf(", \"embree\": %.6f},\n  \"bytes_per_triangle\": {", embree_build);
    double tris = (double)c->scene.triangle_count;
    for (int s = 0; s < 3; s++)
        if (c->wide[s].width)
            printf("\"lanes_wide_%d\": %.2f, ", c->wide[s].width, (double)lanes_wbvh_bytes(&c->wide[s]) / tris);
    printf("\"embree\": %.2f},\n  \"rows\": [\n", lanes_embree_bvh_bytes(c->embree) / tris);
    for (size_t i = 0; i < c->res.count; i++) {
        const row *w = &c->res.rows[i];
        printf("    {\"rays\": \"%s\", \"engine\": \"%s\", \"method\": ", kind_names[w->kind],
               w->embree ? "embree" : "lanes");
        cli_json_string(stdout, w->method);
        printf(", \"isa\": ");
        cli_json_string(stdout, w->isa);
        if (!w->embree) printf(", \"node_width\": %d", set_kernels(c, lanes_isa_from_name(w->isa))->wide_width);
        if (w->counted)
            printf(", \"per_ray\": {\"nodes\": %.4f, \"leaves\": %.4f, \"triangles\": %.4f, "
                   "\"node_utilization\": %.4f, \"leaf_utilization\": %.4f}",
                   w->nodes, w->leaves, w->triangles, w->node_util, w->leaf_util);
        printf(", \"threads\": %d, \"mrays\": %.4f, \"ratio\": %.4f}%s\n", w->threads, w->mrays,
               w->ratio, i + 1 < c->res.count ? "," : "");
    }
    printf("  ],\n  \"agreement\": [\n");
    for (size_t i = 0; i < c->res.agree_count; i++) {
        const agreement *a = &c->res.agree[i];
        printf("    {\"isa\": \"%s\", \"rays\": \"%s\", \"fraction\": %.6f, \"count\": %zu, "
               "\"agree\": %zu, \"lanes_wrong\": %zu, \"embree_wrong\": %zu, \"both_acceptable\": %zu}%s\n",
               lanes_isa_name(a->isa), kind_names[a->kind],
               a->rays ? (double)a->agree / (double)a->rays : 1.0, a->rays, a->agree, a->differ.lanes_wrong,
               a->differ.embree_wrong, a->differ.both_acceptable, i + 1 < c->res.agree_count ? "," : "");
    }
    printf("  ]\n}\n");
}

static const char usage[] =
    "usage: lanes compare [SCENE] [--isa NAME] [--embree-isa NAME] [--threads N]\n"
    "                     [--rays N] [--reps N] [--accuracy M] [--scale S]\n"
    "                     [--translate T] [--node-width N] [--csv FILE] [--json]\n"
    "                     [--stats] [--quick]\n"
    "\n"
    "Traces the same rays through lanes (every supported set; \"single\" = BVH2,\n"
    "\"wide\" = the set's wide BVH (or --node-width's), \"hybrid\" = packets of the\n"
    "set's lane count on the wide BVH, \"packet\" = 1024-ray partition packets on the BVH2,\n"
    "\"stream\" = rays sorted by octant, in groups of 32 through the wide BVH) and\n"
    "through Embree (each of rtcIntersect1/4/8/16/1M/Np, default and coherent\n"
    "contexts; rtcOccluded* for shadow rays), on one pinned thread and on N, and\n"
    "prints Mrays/s with the ratio to the best Embree API for the same rays and\n"
    "threads.\n"
    "\n"
    "  SCENE              built-in name or scene/mesh file (default: default)\n"
    "  --isa NAME         only this lanes set (default: every supported set, or\n"
    "                     LANES_ISA's; LANES_MAX_ISA caps them)\n"
    "  --embree-isa NAME  Embree's kernels: sse2, sse4.2, avx, avx2, avx512\n"
    "                     (default: the best this CPU runs)\n"
    "  --threads N        the all-threads figure uses N threads (default: all\n"
    "                     CPUs this process may run on); 1: single thread only\n"
    "  --rays N           about N camera rays, in the camera's aspect (default 262144,\n"
    "                     512x512); shadow and diffuse rays start at their hits\n"
    "  --reps N           timed repetitions, median reported (default 5)\n"
    "  --accuracy M       lanes' accuracy mode: fast, default (Moller, exact 1/d) or\n"
    "                     robust (watertight, widened boxes); see lanes render --explain\n"
    "  --scale S, --translate T\n"
    "                     the scene (triangles, lights, camera) scaled by S about the\n"
    "                     origin, then moved by T along every axis (default 1, 0):\n"
    "                     the same rays' numerical difficulty at another scale and\n"
    "                     distance from the origin\n"
    "  --node-width N     every set on wide BVHs of N children (4, 8, 16; default:\n"
    "                     each set's own); a set traverses node widths from its\n"
    "                     lane count up: the sets that cannot are left out\n"
    "  --csv FILE         also write the table rows to FILE\n"
    "  --json             one JSON object on stdout instead of the table\n"
    "  --stats            after the timed runs, one counted run of each lanes scheme\n"
    "                     but packet (lanes study counts packets): node and leaf\n"
    "                     visits, triangles tested and the lane utilisation of node\n"
    "                     and triangle tests, per ray (JSON: each row's per_ray)\n"
    "  --quick            16384 camera rays, 2 repetitions (a smoke test)\n"
    "\n"
    "rays: primary (8x8 tiles, Morton order inside), shadow (primary hit to the\n"
    "first point light), diffuse (one cosine-weighted bounce per primary hit,\n"
    "fixed seed) and diffuse-shuffled (the same rays in random order).\n"
    "\n"
    "agreement: each set's wide traversal against rtcIntersect1 / rtcOccluded1 on the\n"
    "same rays; every ray they disagree on is judged by the exact reference of lanes\n"
    "accuracy (each engine's float triangle test's rounding bound around the exact\n"
    "edge functions and t): lanes wrong, Embree wrong, or both acceptable (a true tie\n"
    "or graze).\n";

static int allowed_cpus(int *cpus, int max)
{
    cpu_set_t set;
    int n = 0;
    if (sched_getaffinity(0, sizeof set, &set) != 0) {
        cpus[0] = 0;
        return 1;
    }
    for (int i = 0; i < CPU_SETSIZE && n < max; i++)
        if (CPU_ISSET(i, &set)) cpus[n++] = i;
    if (n == 0) cpus[n++] = 0;
    return n;
}

static int compare_run(cli_context *ctx, const cli_command *self, int argc, char **argv)
{
    compare *c = calloc(1, sizeof *c);
    if (!c) cli_fail("compare: out of memory");
    options *o = &c->opt;
    int cpus[MAX_THREADS];
    int ncpus = allowed_cpus(cpus, MAX_THREADS);
    o->scene_spec = "default";
    o->threads = ncpus;
    o->rays = -1;
    o->reps = -1;
    o->accuracy = LANES_ACCURACY_DEFAULT;
    o->scale = 1.0;
    o->embree_isa = lanes_embree_isa_best();
    o->isa_given = ctx->forced_isa != LANES_ISA_NONE;
    o->isa = ctx->forced_isa;
    bool scene_given = false;

    cli_args a = cli_args_begin(ctx, self, argc, argv);
    const char *v;
    while (cli_args_next(&a)) {
        if (cli_flag(&a, "--json")) {
            o->json = true;
        } else if (cli_flag(&a, "--quick")) {
            o->quick = true;
        } else if (cli_flag(&a, "--stats")) {
            o->stats = true;
        } else if (cli_value(&a, "--csv", &v)) {
            o->csv = v;
        } else if (cli_value(&a, "--threads", &v)) {
            o->threads = (int)cli_parse_count(&a, "--threads", v, 1, MAX_THREADS);
        } else if (cli_value(&a, "--rays", &v)) {
            o->rays = (long)cli_parse_count(&a, "--rays", v, 1, 4096L * 4096L);
        } else if (cli_value(&a, "--accuracy", &v)) {
            int m = lanes_accuracy_from_name(v);
            if (m < 0) cli_usage_error(ctx, self, "--accuracy: unknown mode '%s' (fast, default, robust)", v);
            o->accuracy = (lanes_accuracy)m;
        } else if (cli_value(&a, "--scale", &v)) {
            o->scale = cli_parse_real(&a, "--scale", v, 1e-30, 1e30);
        } else if (cli_value(&a, "--translate", &v)) {
            o->translate = cli_parse_real(&a, "--translate", v, -1e30, 1e30);
        } else if (cli_value(&a, "--node-width", &v)) {
            o->node_width = (int)cli_parse_count(&a, "--node-width", v, 4, 16);
            if (o->node_width != 4 && o->node_width != 8 && o->node_width != 16)
                cli_usage_error(ctx, self, "--node-width: %s is not 4, 8 or 16", v);
        } else if (cli_value(&a, "--reps", &v)) {
            o->reps = (int)cli_parse_count(&a, "--reps", v, 1, 64);
        } else if (cli_value(&a, "--embree-isa", &v)) {
            o->embree_isa = lanes_embree_isa_from_name(v);
            if (o->embree_isa == LANES_EMBREE_ISA_NONE)
                cli_usage_error(ctx, self, "--embree-isa: unknown Embree ISA '%s' (valid: %s)", v,
                                lanes_embree_isa_all_names());
            if (!lanes_embree_isa_cpu_can_run(o->embree_isa))
                cli_fail("--embree-isa %s: this CPU cannot run Embree's %s kernels", v, v);
        } else if (cli_global_option(&a)) {
            o->isa_given = true;
            o->isa = ctx->forced_isa;
        } else if (a.argv[a.i][0] != '-' && !scene_given) {
            o->scene_spec = a.argv[a.i];
            scene_given = true;
        } else {
            cli_unknown_option(&a);
        }
    }
    if (o->rays < 0) o->rays = o->quick ? 128 * 128 : 512 * 512;
    if (o->reps < 0) o->reps = o->quick ? 2 : 5;
    /* Opened now: a path that cannot be written fails before the minutes
     * of measuring, not after. */
    FILE *csv = o->csv ? cli_create_file("compare: --csv", o->csv) : NULL;

    lanes_error err;
    memset(&err, 0, sizeof err);
    if (lanes_scene_load(o->scene_spec, &c->scene, &err) != LANES_OK) cli_fail("%s", err.message);
    if (c->scene.triangle_count == 0) cli_fail("compare: scene '%s' has no triangles", o->scene_spec);
    if ((o->scale != 1.0 || o->translate != 0.0) &&
        lanes_scene_scale_translate(&c->scene, o->scale, o->translate, &err) != LANES_OK)
        cli_fail("compare: %s: %s", o->scene_spec, err.message);

    /* The lanes sets to measure: every supported one, unless the user chose
     * a set (--isa, or LANES_ISA, already validated by lanes_isa_init) or
     * capped them (LANES_MAX_ISA). */
    const char *env_isa = getenv("LANES_ISA"), *env_cap = getenv("LANES_MAX_ISA");
    if (!o->isa_given && env_isa && *env_isa) {
        o->isa_given = true;
        o->isa = lanes_isa_current();
    }
    lanes_isa cap = env_cap && *env_cap ? lanes_isa_from_name(env_cap) : LANES_ISA_NONE;
    /* In rising preference, as the study lists them; the cap is a place in
     * that order (lanes_isa_ranked), not in the enum's. */
    const lanes_isa *ranked = lanes_isa_ranked();
    bool below_cap = true; /* from the worst set up to the cap */
    for (int i = LANES_ISA_COUNT - 1; i >= 0; i--) {
        lanes_isa isa = ranked[i];
        bool want = o->isa_given ? isa == o->isa : lanes_isa_supported(isa) && below_cap;
        if (want && o->node_width && !lanes_kernels_for_width(isa, o->node_width)) {
            if (o->isa_given)
                cli_fail("compare: --node-width %d: the %s set (%d lanes) traverses nodes of %d children or more",
                         o->node_width, lanes_isa_name(isa), lanes_isa_lanes(isa),
                         lanes_kernels_for(isa)->wide_width);
            want = false;
        }
        if (want) c->isas[c->isa_count++] = isa;
        if (isa == cap) below_cap = false;
    }
    if (c->isa_count == 0) cli_fail("compare: no instruction set to measure");
    c->ref_isa = c->isas[c->isa_count - 1];
    for (int i = 0; i < c->isa_count; i++)
        if (c->isas[i] == lanes_isa_best()) c->ref_isa = c->isas[i];

    /* Pinned for the whole run, the builds included: the single-thread pool
     * pins this thread to cpus[0] until it stops. */
    lanes_pool_start(&c->pools[0], 1, cpus, ncpus);
    c->pool_count = 1;

    char features[512];
    lanes_cpu_feature_list(lanes_cpu()->bits, features, sizeof features);
    if (!o->json) {
        printf("cpu:      %s\n", cli_cpu_description());
        printf("compiler: %s\n", cli_compiler());
        printf("features: %s\n", features);
        printf("lanes:    ");
        for (int i = 0; i < c->isa_count; i++)
            printf("%s%s (%d lane%s, %d-wide BVH)", i ? ", " : "", lanes_isa_name(c->isas[i]),
                   lanes_isa_lanes(c->isas[i]), lanes_isa_lanes(c->isas[i]) == 1 ? "" : "s",
                   set_kernels(c, c->isas[i])->wide_width);
        printf(", accuracy %s", lanes_accuracy_name(o->accuracy));
        printf("\nembree:   %s, ISA %s\n", RTC_VERSION_STRING, lanes_embree_isa_name(o->embree_isa));
        printf("scene:    %s (%zu triangles", c->scene.name[0] ? c->scene.name : o->scene_spec,
               c->scene.triangle_count);
        if (o->scale != 1.0 || o->translate != 0.0)
            printf("; scaled by %g, moved by %g on every axis", o->scale, o->translate);
        printf(")\n");
        fflush(stdout);
    }

    /* builds: lanes' BVH2, each width a measured set needs, Embree's BVH */
    lanes_bvh_build_options bo;
    lanes_bvh_default_options(&bo);
    bo.threads = o->threads;
    if (lanes_bvh2_build(&c->scene, &bo, &c->bvh2, &err) != LANES_OK) cli_fail("compare: %s", err.message);
    if (hits_judge_init(&c->judge, &c->scene, &c->bvh2, o->accuracy == LANES_ACCURACY_ROBUST, &err) != LANES_OK)
        cli_fail("compare: %s", err.message);
    bool need[3] = {false, false, false};
    for (int i = 0; i < c->isa_count; i++)
        need[width_slot(set_kernels(c, c->isas[i])->wide_width)] = true;
    for (int s = 0; s < 3; s++)
        if (need[s] && lanes_wbvh_build(&c->scene, 4 << s, &bo, &c->wide[s], &err) != LANES_OK)
            cli_fail("compare: %s", err.message);
    if (lanes_embree_create(&c->scene, o->embree_isa, o->threads, &c->embree, &err) != LANES_OK)
        cli_fail("compare: %s", err.message);
    double eb = lanes_embree_build_seconds(c->embree);
    if (!o->json) {
        printf("build:    lanes BVH2 %.2f ms", c->bvh2.build_seconds * 1e3);
        for (int s = 0; s < 3; s++)
            if (c->wide[s].width)
                printf(", %d-wide %.2f ms (collapse %.2f)", c->wide[s].width, c->wide[s].build_seconds * 1e3,
                       c->wide[s].collapse_seconds * 1e3);
        printf("; Embree commit %.2f ms (%d thread%s)\n", eb * 1e3, o->threads,
               o->threads == 1 ? "" : "s");
        printf("          lanes/Embree build time:");
        for (int s = 0; s < 3; s++)
            if (c->wide[s].width)
                printf(" %.2f (%d-wide)", c->wide[s].build_seconds / eb,
                       c->wide[s].width);
        printf("\n");
        double tris = (double)c->scene.triangle_count;
        printf("memory:   Embree BVH %.1f B/triangle", lanes_embree_bvh_bytes(c->embree) / tris);
        for (int s = 0; s < 3; s++) {
            lanes_bvh_stats st;
            if (!c->wide[s].width || !lanes_wbvh_stats(&c->wide[s], 1.0f, 1.0f, &st)) continue;
            printf("; lanes %d-wide %.1f B/triangle (%.2fx), %.1f children/node, leaf blocks %.0f%% full, "
                   "SAH cost %.3f",
                   c->wide[s].width, (double)st.bytes / tris, (double)st.bytes / lanes_embree_bvh_bytes(c->embree),
                   st.avg_children, 100.0 * st.block_fill, st.sah_cost);
        }
        printf("\n");
        fflush(stdout);
    }

    /* threads */
    if (o->threads > 1) {
        lanes_pool_start(&c->pools[1], o->threads, cpus, ncpus);
        if (c->pools[1].threads != o->threads)
            cli_fail("compare: could start only %d of %d threads", c->pools[1].threads, o->threads);
        c->pool_count = 2;
    }

    /* rays */
    float aspect = (float)c->scene.camera.width / (float)c->scene.camera.height;
    if (!(aspect > 0.0f) || !isfinite(aspect)) aspect = 1.0f;
    c->width = (int)lroundf(sqrtf((float)o->rays * aspect));
    if (c->width < 1) c->width = 1;
    c->height = (int)lround((double)o->rays / c->width);
    if (c->height < 1) c->height = 1;
    size_t np = 0;
    lanes_ray *primary = ray_set_camera(&c->scene, c->width, c->height, RAY_ORDER_MORTON8, &np);
    lanes_hit *phits = malloc(np * sizeof *phits);
    if (!primary || !phits) cli_fail("compare: out of memory for %zu rays", np);
    {
        lanes_job job = {.k = set_kernels(c, c->ref_isa), .scheme = LANES_SCHEME_WIDE, .bvh2 = &c->bvh2,
                         .wide = &c->wide[width_slot(set_kernels(c, c->ref_isa)->wide_width)],
                         .rays = primary, .hits = phits};
        pool_run(&c->pools[c->pool_count - 1], lanes_work, &job, np);
    }
    size_t npts = 0, nshadow = 0;
    surface_point *pts = ray_set_surface_points(&c->scene, primary, phits, np, &npts);
    lanes_ray *shadow = pts ? ray_set_shadow(&c->scene, pts, npts, &nshadow) : NULL;
    lanes_ray *diffuse = pts ? ray_set_diffuse(pts, npts) : NULL;
    lanes_ray *shuffle = diffuse ? ray_set_shuffled(diffuse, npts) : NULL;
    if (!shuffle || !shadow) cli_fail("compare: out of memory for the secondary rays");
    if (!o->json) {
        printf("rays:     %dx%d camera rays (%zu hit), %zu shadow, %zu diffuse; median of %d runs\n\n",
               c->width, c->height, npts, nshadow, npts, o->reps);
        fflush(stdout);
    }

    run_kind(c, KIND_PRIMARY, primary, np);
    run_kind(c, KIND_SHADOW, shadow, nshadow);
    run_kind(c, KIND_DIFFUSE, diffuse, npts);
    run_kind(c, KIND_SHUFFLED, shuffle, npts);

    for (int i = c->pool_count - 1; i >= 0; i--) lanes_pool_stop(&c->pools[i]);

    int status = 0;
    if (o->json) {
        print_json(c, eb);
    } else {
        print_table(stdout, c);
        if (o->stats) print_counts(stdout, c);
        printf("\nagreement of lanes (wide, %s) with Embree (rtcIntersect1 / rtcOccluded1, Moller):\n"
               "same primitive and t within 1e-4 relative, or both miss; shadow rays: same\n"
               "occlusion. Each difference judged by the exact reference: an answer is wrong\n"
               "when the float test's proven rounding bound cannot explain it; both acceptable\n"
               "when both can be (a true tie or graze).\n",
               judge_test_of(o->accuracy) == JUDGE_WATERTIGHT ? "watertight" : "Moller");
        for (size_t i = 0; i < c->res.agree_count; i++) {
            const agreement *ag = &c->res.agree[i];
            printf("  %-10s %-17s %8.4f%%  (%zu of %zu differ: %zu lanes wrong, %zu Embree wrong, "
                   "%zu both acceptable)\n",
                   lanes_isa_name(ag->isa), kind_names[ag->kind],
                   ag->rays ? 100.0 * (double)ag->agree / (double)ag->rays : 100.0, ag->rays - ag->agree,
                   ag->rays, ag->differ.lanes_wrong, ag->differ.embree_wrong, ag->differ.both_acceptable);
        }
    }
    if (csv) write_csv(csv, o->csv, c);
    if (fflush(stdout) != 0) status = 1;

    free(primary);
    free(phits);
    free(pts);
    free(shadow);
    free(diffuse);
    free(shuffle);
    free(c->res.rows);
    lanes_embree_destroy(c->embree);
    for (int s = 0; s < 3; s++)
        if (c->wide[s].width) lanes_wbvh_free(&c->wide[s]);
    hits_judge_free(&c->judge);
    lanes_bvh2_free(&c->bvh2);
    lanes_scene_free(&c->scene);
    free(c);
    return status;
}

const cli_command cli_cmd_compare = {
    .name = "compare",
    .summary = "lanes against Embree on the same rays: Mrays/s, ratios, agreement",
    .usage = usage,
    .run = compare_run,
};

int lanes_cmd_compare(int argc, char **argv)
{
    cli_context ctx = {.forced_isa = LANES_ISA_NONE, .path = "lanes compare"};
    return compare_run(&ctx, &cli_cmd_compare, argc, argv);
}
