/* `lanes bench kernels`: throughput of the hot kernels at every instruction
 * set, single-threaded, each figure set against the throughput bound of
 * kernel_model.h.
 *
 * Method:
 * - One thread pinned to one CPU, so the figures do not mix cores or pay
 *   for migrations.
 * - Every set reads the same inputs (kernel_inputs.c), prepared once.
 * - A run repeats a batch of kernel calls for about --run-ms; each
 *   (kernel, set) gets --reps runs and the median counts. The sets take
 *   turns within each repetition, so slow drift of the machine touches
 *   them alike and the ratios between them stay fair.
 * - Timed runs pass stats = NULL (the copy of each body without counting);
 *   lane utilisation comes from one separate counting run.
 * - The instruction count comes from single-stepping sample calls
 *   (kernel_model.c), never from the timed runs. */
#define _GNU_SOURCE /* sched_setaffinity, sched_getcpu, CPU_SET */

#include <errno.h>
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bench/cli_commands.h"
#include "bench/cli_common.h"
#include "bench/kernel_inputs.h"
#include "bench/kernel_model.h"
#include "bench/pipe_rates.h"
#include "trace/kernels.h"

/* ---- the kernels under test -------------------------------------------- */

typedef struct outputs {
    uint32_t *bits;  /* hit or keep bits */
    float *tentry;   /* box entry distances */
    lanes_tri_hits tri;
    lanes_frustum frustum;
} outputs;

typedef struct env {
    const lanes_kernels *k;
    const kernel_inputs *in;
    outputs *out;
} env;

/* One kernel call: primitive j against n rays (packet form), or ray j
 * against n primitives (wide form). Returns the kernel's hit or keep count. */
typedef size_t (*case_call)(const env *e, size_t j, size_t n, lanes_lane_stats *st);
typedef uintptr_t (*case_entry)(const lanes_kernels *k);

enum { TRUTH_NONE, TRUTH_BOXES, TRUTH_TRIS };

typedef struct bench_case {
    const char *kernel, *form;
    const char *what;     /* "<n> <what>; <calls> calls per batch" describes the work */
    size_t calls;         /* calls in one batch */
    size_t n;             /* elements (tests) per call */
    case_call call;
    case_entry entry;
    bool counts_hits;     /* the return value is a number of hits or kept primitives */
    int truth;            /* culling: which primitives some ray really hits */
} bench_case;

static size_t c_box_packet(const env *e, size_t j, size_t n, lanes_lane_stats *st)
{
    return e->k->box_packet(&e->in->packet, NULL, n, &e->in->packet_boxes[j], e->out->bits,
                            e->out->tentry, st);
}
static uintptr_t x_box_packet(const lanes_kernels *k) { return (uintptr_t)k->box_packet; }

static size_t c_box_wide(const env *e, size_t j, size_t n, lanes_lane_stats *st)
{
    return e->k->box_wide(&e->in->wide_rays[j], &e->in->wide_boxes, n, e->out->bits,
                          e->out->tentry, st);
}
static uintptr_t x_box_wide(const lanes_kernels *k) { return (uintptr_t)k->box_wide; }

#define TRI_CASES(algo, ALGO)                                                              \
    static size_t c_tri_packet_##algo(const env *e, size_t j, size_t n, lanes_lane_stats *st) \
    {                                                                                      \
        return e->k->tri_packet[ALGO](&e->in->packet, NULL, n, &e->in->packet_tris[j],     \
                                      e->out->bits, &e->out->tri, st);                     \
    }                                                                                      \
    static uintptr_t x_tri_packet_##algo(const lanes_kernels *k)                           \
    {                                                                                      \
        return (uintptr_t)k->tri_packet[ALGO];                                             \
    }                                                                                      \
    static size_t c_tri_wide_##algo(const env *e, size_t j, size_t n, lanes_lane_stats *st) \
    {                                                                                      \
        return e->k->tri_wide[ALGO](&e->in->wide_rays[j], &e->in->wide_tris, n,            \
                                    e->out->bits, &e->out->tri, st);                       \
    }                                                                                      \
    static uintptr_t x_tri_wide_##algo(const lanes_kernels *k)                             \
    {                                                                                      \
        return (uintptr_t)k->tri_wide[ALGO];                                               \
    }
TRI_CASES(moller, LANES_TRI_MOLLER)
TRI_CASES(watertight, LANES_TRI_WATERTIGHT)

#define CULL_CASE(prims, method, METHOD, field)                                            \
    static size_t c_frustum_##prims##_##method(const env *e, size_t j, size_t n,           \
                                               lanes_lane_stats *st)                       \
    {                                                                                      \
        (void)j;                                                                           \
        return e->k->frustum_##prims(&e->in->frustum, &e->in->field, n, METHOD, e->out->bits, \
                                     st);                                                  \
    }
CULL_CASE(boxes, interval, LANES_CULL_INTERVAL, cull_boxes)
CULL_CASE(boxes, planes, LANES_CULL_PLANES, cull_boxes)
CULL_CASE(tris, interval, LANES_CULL_INTERVAL, cull_tris)
CULL_CASE(tris, planes, LANES_CULL_PLANES, cull_tris)
static uintptr_t x_frustum_boxes(const lanes_kernels *k) { return (uintptr_t)k->frustum_boxes; }
static uintptr_t x_frustum_tris(const lanes_kernels *k) { return (uintptr_t)k->frustum_tris; }

static uint64_t fnv_floats(uint64_t h, const float *v, int n)
{
    for (int i = 0; i < n; i++) {
        uint32_t bits;
        memcpy(&bits, &v[i], sizeof bits);
        h = (h ^ bits) * 1099511628211ull;
    }
    return h;
}

/* A digest of a frustum's bits, to check that every set builds the same
 * one (all of it is min/max, exact division and unfused arithmetic). */
static uint64_t frustum_digest(const lanes_frustum *f)
{
    const float scalars[] = {f->tnear, f->tfar, f->near, f->ksign};
    const float *vectors[] = {f->omin, f->omax, f->dmin, f->dmax, f->rmin, f->rmax,
                              f->lo0,  f->lo_slope, f->hi0, f->hi_slope};
    uint64_t h = fnv_floats(1469598103934665603ull, scalars, 4);
    for (size_t g = 0; g < sizeof vectors / sizeof vectors[0]; g++) h = fnv_floats(h, vectors[g], 3);
    uint32_t flags = (uint32_t)f->valid | (uint32_t)f->empty << 1 | (uint32_t)f->has_planes << 2 |
                     (uint32_t)f->ia_axis_ok[0] << 3 | (uint32_t)f->ia_axis_ok[1] << 4 |
                     (uint32_t)f->ia_axis_ok[2] << 5 | (uint32_t)f->k << 6;
    return (h ^ flags) * 1099511628211ull;
}

static size_t c_frustum_build(const env *e, size_t j, size_t n, lanes_lane_stats *st)
{
    (void)j;
    e->k->frustum_build(&e->in->packet, NULL, n, &e->out->frustum);
    if (!st) return e->out->frustum.valid;
    /* frustum_build takes no stats: both of its passes run over all n rays,
     * so the lanes it fills follow from n and the width. */
    size_t w = (size_t)e->k->lanes, iters = (n + w - 1) / w;
    st->vector_ops += iters;
    st->lane_slots += iters * w;
    st->active_lanes += n;
    return (size_t)frustum_digest(&e->out->frustum);
}
static uintptr_t x_frustum_build(const lanes_kernels *k) { return (uintptr_t)k->frustum_build; }

static const bench_case cases[] = {
    {"box", "packet", "rays x 1 box, tentry written", KI_PACKET_PRIMS, KI_PACKET_RAYS,
     c_box_packet, x_box_packet, true, TRUTH_NONE},
    {"box", "wide", "boxes (SoA) x 1 ray, tentry written", KI_WIDE_RAYS, KI_WIDE_COUNT,
     c_box_wide, x_box_wide, true, TRUTH_NONE},
    {"tri_moller", "packet", "rays x 1 triangle, t/u/v written", KI_PACKET_PRIMS,
     KI_PACKET_RAYS, c_tri_packet_moller, x_tri_packet_moller, true, TRUTH_NONE},
    {"tri_moller", "wide", "triangles (SoA) x 1 ray, t/u/v written", KI_WIDE_RAYS,
     KI_WIDE_COUNT, c_tri_wide_moller, x_tri_wide_moller, true, TRUTH_NONE},
    {"tri_watertight", "packet", "rays x 1 triangle, t/u/v written", KI_PACKET_PRIMS,
     KI_PACKET_RAYS, c_tri_packet_watertight, x_tri_packet_watertight, true, TRUTH_NONE},
    {"tri_watertight", "wide", "triangles (SoA) x 1 ray, t/u/v written", KI_WIDE_RAYS,
     KI_WIDE_COUNT, c_tri_wide_watertight, x_tri_wide_watertight, true, TRUTH_NONE},
    {"frustum_boxes_interval", "wide", "boxes x the packet's frustum, LANES_CULL_INTERVAL", 1,
     KI_CULL_COUNT, c_frustum_boxes_interval, x_frustum_boxes, true, TRUTH_BOXES},
    {"frustum_boxes_planes", "wide", "boxes x the packet's frustum, LANES_CULL_PLANES", 1,
     KI_CULL_COUNT, c_frustum_boxes_planes, x_frustum_boxes, true, TRUTH_BOXES},
    {"frustum_tris_interval", "wide", "triangles x the packet's frustum, LANES_CULL_INTERVAL", 1,
     KI_CULL_COUNT, c_frustum_tris_interval, x_frustum_tris, true, TRUTH_TRIS},
    {"frustum_tris_planes", "wide", "triangles x the packet's frustum, LANES_CULL_PLANES", 1,
     KI_CULL_COUNT, c_frustum_tris_planes, x_frustum_tris, true, TRUTH_TRIS},
    {"frustum_build", "packet", "rays into one frustum (both passes; a test = a ray)", 4,
     KI_PACKET_RAYS, c_frustum_build, x_frustum_build, false, TRUTH_NONE},
};
#define NCASES (sizeof cases / sizeof cases[0])

/* ---- options ----------------------------------------------------------- */

typedef struct options {
    bool all;
    const char *csv;
    unsigned long reps;
    unsigned long run_ms;
    unsigned long issue_width; /* 0: from the core table */
    bool quick;
    bool count;
} options;

/* Instruction counting samples: calls of m and 2m vector iterations (the
 * first m*W and 2m*W elements) for `samples` different rays or primitives.
 * The difference gives the cost per iteration, the rest the cost per call.
 * Each single step costs microseconds, so the sample sizes follow a budget
 * of steps per kernel and set. */
typedef struct sample_plan {
    size_t samples, m;
} sample_plan;

/* ---- results ----------------------------------------------------------- */

/* The instruction classes the resource bound charges (kernel_model.h). */
enum { C_VEC, C_MUL, C_ADD, C_LOAD, C_STORE, C_MASKSTORE, NCLASS };
static const int class_bit[NCLASS] = {KM_VECTOR, KM_MUL, KM_ADD, KM_LOAD, KM_STORE, KM_MASKSTORE};

typedef struct result {
    double ns_per_test;  /* median */
    double cpu_share;    /* median of thread CPU time / wall time over the timed runs */
    double utilization;  /* active lanes / lane slots */
    uint64_t answer;     /* summed return values of one batch: compared across sets */
    size_t batches;
    /* instruction model */
    bool counted;
    char count_error[160];
    sample_plan plan;
    size_t culled_hit;   /* culling: primitives some ray hits that were culled anyway */
    km_site *sites[2];   /* executed addresses of the m- and 2m-iteration samples */
    size_t nsites[2];
    double instr[2];     /* instructions summed over the m- and 2m-iteration samples */
    double ipi;          /* instructions per vector iteration of a timed call */
    bool classified;     /* cls_ipi holds the instruction classes */
    double cls_ipi[2][NCLASS]; /* per iteration, by class; [1]: on zmm registers */
} result;

static volatile size_t sink; /* keeps the kernels' results alive */

static double mtests(const result *r) { return r->ns_per_test > 0 ? 1e3 / r->ns_per_test : 0; }

/* ---- measuring --------------------------------------------------------- */

/* Wall time of `batches` batches; *cpu_share (if not NULL) receives the
 * thread's CPU time over that wall time: below 1 the run was preempted. */
static double run_batches(const bench_case *c, const env *e, size_t batches, double *cpu_share)
{
    size_t acc = 0;
    uint64_t c0 = cpu_share ? cli_thread_cpu_ns() : 0;
    uint64_t t0 = cli_now_ns();
    for (size_t b = 0; b < batches; b++)
        for (size_t j = 0; j < c->calls; j++) acc += c->call(e, j, c->n, NULL);
    uint64_t t1 = cli_now_ns();
    if (cpu_share) {
        uint64_t c1 = cli_thread_cpu_ns();
        *cpu_share = t1 > t0 && c1 >= c0 ? (double)(c1 - c0) / (double)(t1 - t0) : 1.0;
    }
    sink += acc;
    return (double)(t1 - t0);
}

/* Batches that make a run last about target_ns. */
static size_t calibrate(const bench_case *c, const env *e, double target_ns)
{
    size_t b = 1;
    double t;
    run_batches(c, e, 1, NULL); /* warm caches, branch predictors and the page tables */
    for (;;) {
        t = run_batches(c, e, b, NULL);
        if (t >= target_ns / 8 || b >= ((size_t)1 << 30)) break;
        b *= 4;
    }
    double want = (double)b * target_ns / (t > 1 ? t : 1);
    return want < 1 ? 1 : (size_t)want;
}

static void counting_run(const bench_case *c, const env *e, result *r)
{
    lanes_lane_stats st = {0, 0, 0};
    uint64_t answer = 0;
    for (size_t j = 0; j < c->calls; j++) answer += c->call(e, j, c->n, &st);
    r->answer = answer;
    r->utilization = st.lane_slots ? (double)st.active_lanes / (double)st.lane_slots : -1.0;
}

typedef struct trace_arg {
    const bench_case *c;
    const env *e;
    size_t j, n;
} trace_arg;

static void trace_thunk(void *p)
{
    const trace_arg *a = p;
    sink += a->c->call(a->e, a->j, a->n, NULL);
}

static void count_instructions(const bench_case *c, const env *e, size_t max_samples,
                               double budget, result *r)
{
    uintptr_t entry = c->entry(e->k);
    size_t w = (size_t)e->k->lanes;
    uint64_t probe = 0;

    /* One iteration first: an upper estimate of the steps an iteration takes. */
    km_trace_reset();
    trace_arg pa = {c, e, 0, w};
    if (!km_trace_call(entry, trace_thunk, &pa, &probe, r->count_error, sizeof r->count_error))
        return;
    sample_plan plan = {max_samples, 0};
    double per_iter = probe > 0 ? (double)probe : 1.0;
    for (;;) {
        plan.m = (size_t)(budget / (3.0 * (double)plan.samples * per_iter));
        if (plan.m >= 1 || plan.samples == 1) break;
        plan.samples /= 2;
    }
    if (plan.m < 1) plan.m = 1;
    if (plan.m * 2 * w > c->n) plan.m = c->n / (2 * w);
    r->plan = plan;

    for (int s = 0; s < 2; s++) {
        km_trace_reset();
        r->instr[s] = 0;
        for (size_t k = 0; k < plan.samples; k++) {
            trace_arg a = {c, e, k % c->calls, plan.m * w * (size_t)(s + 1)};
            uint64_t n = 0;
            if (!km_trace_call(entry, trace_thunk, &a, &n, r->count_error, sizeof r->count_error))
                return;
            r->instr[s] += (double)n;
        }
        r->nsites[s] = km_trace_sites(&r->sites[s]);
    }
    r->counted = true;
}

/* Per-iteration and per-call parts from the two sample sizes, then the
 * cost of one iteration of a timed call (per-call part spread over it). */
static double per_timed_iteration(double sum1, double sum2, const sample_plan *plan, size_t w,
                                  size_t n_timed)
{
    double m = (double)plan->m, samples = (double)plan->samples;
    double per_iter = (sum2 - sum1) / (samples * m);
    double per_call = sum1 / samples - per_iter * m;
    double iters = (double)((n_timed + w - 1) / w);
    return per_iter + per_call / iters;
}

static void classify_counts(const bench_case *c, size_t w, const km_disasm *d, result *r)
{
    double sum[2][2][NCLASS] = {{{0}}}; /* [sample size][zmm][class] */
    for (int s = 0; s < 2; s++)
        for (size_t i = 0; i < r->nsites[s]; i++) {
            int cls = km_disasm_class(d, r->sites[s][i].addr);
            if (cls < 0) return;
            for (int k = 0; k < NCLASS; k++)
                if (cls & class_bit[k]) sum[s][(cls & KM_ZMM) != 0][k] += (double)r->sites[s][i].count;
        }
    for (int z = 0; z < 2; z++)
        for (int k = 0; k < NCLASS; k++)
            r->cls_ipi[z][k] = per_timed_iteration(sum[0][z][k], sum[1][z][k], &r->plan, w, c->n);
    r->classified = true;
}

/* ---- the machine ------------------------------------------------------- */

/* Pins the thread to the CPU it runs on (if allowed), else the first allowed. */
static int pin_thread(char *why, size_t size)
{
    cpu_set_t allowed, one;
    if (sched_getaffinity(0, sizeof allowed, &allowed) != 0) {
        snprintf(why, size, "sched_getaffinity failed");
        return -1;
    }
    int cpu = sched_getcpu();
    if (cpu < 0 || cpu >= CPU_SETSIZE || !CPU_ISSET(cpu, &allowed)) {
        cpu = -1;
        for (int i = 0; i < CPU_SETSIZE && cpu < 0; i++)
            if (CPU_ISSET(i, &allowed)) cpu = i;
    }
    if (cpu < 0) {
        snprintf(why, size, "no CPU in the affinity mask");
        return -1;
    }
    CPU_ZERO(&one);
    CPU_SET(cpu, &one);
    if (sched_setaffinity(0, sizeof one, &one) != 0) {
        snprintf(why, size, "sched_setaffinity to CPU %d failed", cpu);
        return -1;
    }
    return cpu;
}

/* ---- output ------------------------------------------------------------ */

/* Mtests/s in 7 columns with 4 significant digits where they fit. */
static const char *fmt_rate(char *buf, size_t size, double v)
{
    if (v < 10)
        snprintf(buf, size, "%7.3f", v);
    else if (v < 100)
        snprintf(buf, size, "%7.2f", v);
    else if (v < 1000)
        snprintf(buf, size, "%7.1f", v);
    else
        snprintf(buf, size, "%7.0f", v);
    return buf;
}

static double issue_bound(const result *r, double hz, int width, int lanes)
{
    return r->counted && r->ipi > 0 ? hz * width * lanes / r->ipi / 1e6 : 0;
}

static void print_row_label(const bench_case *c) { printf("%-22s %-6s", c->kernel, c->form); }

static void print_isa_header(const lanes_isa *isas, size_t nisa, int group_width, const char *sub)
{
    printf("%-29s", "");
    for (size_t i = 0; i < nisa; i++) {
        char h[48];
        snprintf(h, sizeof h, "%s (%d)", lanes_isa_name(isas[i]), lanes_isa_lanes(isas[i]));
        printf(" %*s", group_width - 1, h);
    }
    printf("\n%-22s %-6s", "kernel", "form");
    for (size_t i = 0; i < nisa; i++) printf("%s", sub);
    printf("\n");
}

/* ---- one invocation ---------------------------------------------------- */

typedef struct bench_run {
    options opt;
    lanes_isa isas[LANES_ISA_COUNT];
    size_t nisa;
    km_core core;
    int width;
    double hz, hz_before, hz_after;
    km_pipes pipes;
    size_t max_samples;
    double budget;
    bool count_failed;
    char count_error[160];
    bool classified;
    char class_error[200];
    double min_share; /* smallest median CPU share of any kernel and set */
    /* culling ground truth: bit i set when some packet ray hits primitive i */
    uint32_t *needed[3];
    size_t needed_count[3];
    result res[NCASES][LANES_ISA_COUNT];
} bench_run;

/* The resource bound: an iteration takes at least as many cycles as the
 * scarcest resource it uses needs, each resource's operations over its
 * measured rate (pipe_rates.h). A zmm operation counts as many ymm ones as
 * the measured rates say (two on a core that splits it); min, max and
 * compares are charged to the adders; the mixed rate says whether
 * multiplies and adds share pipes. */
enum { R_ISSUE, R_MUL, R_ADD, R_MUL_ADD, R_VEC, R_LOAD, R_STORE, R_MASKSTORE, NRES };
static const char *const resource_name[NRES] = {"issue", "mul", "add", "mul+add",
                                                "vector", "load", "store", "maskstore"};

static double zmm_weight(double ymm_rate, double zmm_rate)
{
    return zmm_rate > 0 ? ymm_rate / zmm_rate : 1.0;
}

static double resource_cycles(const result *r, const bench_run *b, int res)
{
    const km_pipes *p = &b->pipes;
    const double *y = r->cls_ipi[0], *z = r->cls_ipi[1];
    const double wv = zmm_weight(p->mul, p->zmm_mul);
    switch (res) {
    case R_ISSUE: return r->ipi / b->width;
    case R_MUL: return (y[C_MUL] + wv * z[C_MUL]) / p->mul;
    case R_ADD: return (y[C_ADD] + wv * z[C_ADD]) / p->add;
    case R_MUL_ADD: return (y[C_MUL] + y[C_ADD] + wv * (z[C_MUL] + z[C_ADD])) / p->mul_add;
    case R_VEC: return (y[C_VEC] + wv * z[C_VEC]) / p->any;
    case R_LOAD: return (y[C_LOAD] + zmm_weight(p->load, p->zmm_load) * z[C_LOAD]) / p->load;
    case R_STORE: return (y[C_STORE] + zmm_weight(p->store, p->zmm_store) * z[C_STORE]) / p->store;
    default: return (y[C_MASKSTORE] + z[C_MASKSTORE]) * p->masked_store_cyc;
    }
}

/* The bound in cycles per iteration and the resource that sets it; 0 when
 * the instructions or the rates are unknown. */
static double resource_bound(const result *r, const bench_run *b, int *which)
{
    *which = -1;
    if (!r->counted || !r->classified || !b->pipes.measured) return 0;
    double worst = 0;
    for (int res = 0; res < NRES; res++) {
        double c = resource_cycles(r, b, res);
        if (c > worst) worst = c, *which = res;
    }
    return worst;
}

/* Cycles one vector iteration took in the timed runs. */
static double measured_cycles(const result *r, double hz, int lanes)
{
    return r->ns_per_test * 1e-9 * hz * lanes;
}

/* Which culled primitives some ray of the packet really hits, by the
 * scalar box test and the watertight triangle test. */
static bool make_truth(bench_run *b, const kernel_inputs *in)
{
    const lanes_kernels *k = lanes_kernels_for(LANES_ISA_SCALAR);
    size_t words = lanes_mask_words(KI_PACKET_RAYS);
    uint32_t *scratch = calloc(words, sizeof *scratch);
    b->needed[TRUTH_BOXES] = calloc(lanes_mask_words(KI_CULL_COUNT), sizeof(uint32_t));
    b->needed[TRUTH_TRIS] = calloc(lanes_mask_words(KI_CULL_COUNT), sizeof(uint32_t));
    if (!scratch || !b->needed[TRUTH_BOXES] || !b->needed[TRUTH_TRIS]) {
        free(scratch);
        return false;
    }
    for (size_t i = 0; i < KI_CULL_COUNT; i++) {
        const lanes_boxes *bx = &in->cull_boxes;
        lanes_box box = {{bx->minx[i], bx->miny[i], bx->minz[i]},
                         {bx->maxx[i], bx->maxy[i], bx->maxz[i]}};
        if (k->box_packet(&in->packet, NULL, KI_PACKET_RAYS, &box, scratch, NULL, NULL)) {
            b->needed[TRUTH_BOXES][i / 32] |= 1u << (i % 32);
            b->needed_count[TRUTH_BOXES]++;
        }
        const lanes_triangles *t = &in->cull_tris;
        lanes_triangle tri = {{t->v0x[i], t->v0y[i], t->v0z[i]},
                              {t->v1x[i], t->v1y[i], t->v1z[i]},
                              {t->v2x[i], t->v2y[i], t->v2z[i]}};
        if (k->tri_packet_any[LANES_TRI_WATERTIGHT](&in->packet, NULL, KI_PACKET_RAYS, &tri,
                                                     scratch, NULL)) {
            b->needed[TRUTH_TRIS][i / 32] |= 1u << (i % 32);
            b->needed_count[TRUTH_TRIS]++;
        }
    }
    free(scratch);
    return true;
}

/* A conservative cull keeps every primitive some ray hits. */
static size_t culled_but_hit(const bench_run *b, const bench_case *c, const uint32_t *keep)
{
    size_t bad = 0;
    if (c->truth == TRUTH_NONE) return 0;
    for (size_t i = 0; i < c->n; i++)
        if (lanes_mask_get(b->needed[c->truth], i) && !lanes_mask_get(keep, i)) bad++;
    return bad;
}

static void measure_case(bench_run *b, size_t ci, const kernel_inputs *in, outputs *out,
                         bool progress)
{
    const bench_case *c = &cases[ci];
    env envs[LANES_ISA_COUNT];
    double target_ns = (double)b->opt.run_ms * 1e6;

    if (progress) fprintf(stderr, "\r\033[K%s/%s: counting", c->kernel, c->form);
    for (size_t i = 0; i < b->nisa; i++) {
        envs[i] = (env){lanes_kernels_for(b->isas[i]), in, out};
        result *r = &b->res[ci][i];
        counting_run(c, &envs[i], r);
        r->culled_hit = culled_but_hit(b, c, out->bits); /* culling makes one call per batch */
        if (!b->opt.count || b->count_failed) continue;
        count_instructions(c, &envs[i], b->max_samples, b->budget, r);
        if (!r->counted) {
            b->count_failed = true;
            snprintf(b->count_error, sizeof b->count_error, "%s", r->count_error);
            continue;
        }
        r->ipi = per_timed_iteration(r->instr[0], r->instr[1], &r->plan, (size_t)envs[i].k->lanes,
                                     c->n);
    }

    if (progress) fprintf(stderr, "\r\033[K%s/%s: timing", c->kernel, c->form);
    for (size_t i = 0; i < b->nisa; i++) b->res[ci][i].batches = calibrate(c, &envs[i], target_ns);
    size_t reps = b->opt.reps;
    double *samples = calloc(2 * reps * b->nisa, sizeof *samples), *shares = samples + reps * b->nisa;
    if (!samples) cli_fail("out of memory");
    for (size_t rep = 0; rep < reps; rep++)
        for (size_t i = 0; i < b->nisa; i++) {
            result *r = &b->res[ci][i];
            double ns = run_batches(c, &envs[i], r->batches, &shares[i * reps + rep]);
            samples[i * reps + rep] = ns / ((double)r->batches * c->calls * c->n);
        }
    for (size_t i = 0; i < b->nisa; i++) {
        result *r = &b->res[ci][i];
        r->ns_per_test = cli_median(samples + i * reps, reps);
        r->cpu_share = cli_median(shares + i * reps, reps);
        if (r->cpu_share < b->min_share) b->min_share = r->cpu_share;
    }
    free(samples);
}

/* Classifies the executed instructions: one objdump over the span of all. */
static void classify_all(bench_run *b)
{
    uintptr_t lo = UINTPTR_MAX, hi = 0;
    for (size_t ci = 0; ci < NCASES; ci++)
        for (size_t i = 0; i < b->nisa; i++)
            for (int s = 0; s < 2; s++)
                for (size_t k = 0; k < b->res[ci][i].nsites[s]; k++) {
                    uintptr_t ad = b->res[ci][i].sites[s][k].addr;
                    if (ad < lo) lo = ad;
                    if (ad > hi) hi = ad;
                }
    km_disasm d;
    if (lo > hi || !km_disasm_load(lo, hi, &d, b->class_error, sizeof b->class_error)) return;
    b->classified = true;
    for (size_t ci = 0; ci < NCASES; ci++)
        for (size_t i = 0; i < b->nisa; i++)
            if (b->res[ci][i].counted)
                classify_counts(&cases[ci], (size_t)lanes_isa_lanes(b->isas[i]), &d, &b->res[ci][i]);
    km_disasm_free(&d);
}

static void print_throughput(const bench_run *b)
{
    size_t scalar_col = b->nisa;
    char buf[32];
    for (size_t i = 0; i < b->nisa; i++)
        if (b->isas[i] == LANES_ISA_SCALAR) scalar_col = i;
    printf("\nthroughput: Mt/s = million tests per second (median); bound = fraction of the issue "
           "bound (model below); xS = speedup over scalar\n");
    print_isa_header(b->isas, b->nisa, 21, "    Mt/s bound    xS");
    for (size_t ci = 0; ci < NCASES; ci++) {
        print_row_label(&cases[ci]);
        for (size_t i = 0; i < b->nisa; i++) {
            const result *r = &b->res[ci][i];
            double bound = issue_bound(r, b->hz, b->width, lanes_isa_lanes(b->isas[i]));
            printf(" %s", fmt_rate(buf, sizeof buf, mtests(r)));
            if (bound > 0)
                printf(" %5.2f", mtests(r) / bound);
            else
                printf(" %5s", "n/a");
            if (scalar_col < b->nisa && r->ns_per_test > 0)
                printf(" %5.1fx", b->res[ci][scalar_col].ns_per_test / r->ns_per_test);
            else
                printf(" %6s", "-");
        }
        printf("\n");
    }
}

static void print_model(const bench_run *b)
{
    printf("\nthroughput bound model (no hardware counters on this machine; every input measured "
           "or stated):\n");
    printf("  bound [tests/s] = f_clk * issue_width * lanes / instructions_per_iteration\n");
    printf("  f_clk = %.3f GHz: timed chain of dependent 64-bit adds (1 per cycle), fastest of 7 "
           "runs;\n          %.3f GHz before and %.3f GHz after the measurements, the mean is "
           "used\n",
           b->hz / 1e9, b->hz_before / 1e9, b->hz_after / 1e9);
    if (b->opt.issue_width)
        printf("  issue_width = %d macro-ops/cycle (--issue-width; the table says %d for %s)\n",
               b->width, b->core.issue_width, b->core.name);
    else
        printf("  issue_width = %d macro-ops/cycle for %s:\n    %s\n", b->width, b->core.name,
               b->core.why);
    if (!b->opt.count) {
        printf("  instructions_per_iteration: not counted (--no-count): bounds and fractions n/a\n");
        return;
    }
    if (b->count_failed) {
        printf("  instructions_per_iteration: UNAVAILABLE: %s;\n    bounds and fractions are "
               "n/a\n",
               b->count_error);
        return;
    }
    size_t mlo = SIZE_MAX, mhi = 0;
    for (size_t ci = 0; ci < NCASES; ci++)
        for (size_t i = 0; i < b->nisa; i++) {
            size_t m = b->res[ci][i].plan.m;
            if (m < mlo) mlo = m;
            if (m > mhi) mhi = m;
        }
    printf("  instructions_per_iteration: exact count of the x86 instructions the kernel executes "
           "(stats = NULL\n"
           "    copy), by single-stepping it with the trap flag on the benchmark's own inputs: up "
           "to %zu calls\n"
           "    (different rays or primitives) of m and 2m vector iterations, m = %zu..%zu sized "
           "to a budget of\n"
           "    ~%.0f steps per kernel and set. The difference gives the cost per iteration, the "
           "rest the per-call\n"
           "    cost, spread here over one timed call (%d rays or %d primitives). An instruction "
           "stands for a\n"
           "    macro-op: a fused compare+branch counts 2 but dispatches as 1, so the bound errs "
           "low by up to one\n"
           "    op per branch.\n",
           b->max_samples, mlo, mhi, b->budget, KI_PACKET_RAYS, KI_WIDE_COUNT);
    const km_pipes *p = &b->pipes;
    if (!p->measured) {
        printf("  resource bound: UNAVAILABLE: the CPU lacks AVX, which the pipe probes use\n");
        return;
    }
    printf("  resource bound (a second model): cycles per iteration >= the largest of, per "
           "resource,\n"
           "    its operations per iteration / its rate; rates measured on this core (12 "
           "independent operations\n"
           "    per loop, fastest of 7 runs), per cycle, of 256-bit operations:\n"
           "      mul %.2f (%s)  add %.2f (vaddps; min, max and compares charged here)  mul+add "
           "%.2f (half each)\n"
           "      vector %.2f (vandps: every pipe)  load %.2f  store %.2f  (vmovups)\n",
           p->mul, lanes_cpu()->bits & LANES_CPU_FMA ? "vfmadd231ps" : "vmulps", p->add,
           p->mul_add, p->any, p->load, p->store);
    if (p->zmm_mul > 0)
        printf("      512-bit: mul %.2f load %.2f store %.2f per cycle: a zmm operation counts "
               "%.2f, %.2f, %.2f of 256-bit ones\n",
               p->zmm_mul, p->zmm_load, p->zmm_store, zmm_weight(p->mul, p->zmm_mul),
               zmm_weight(p->load, p->zmm_load), zmm_weight(p->store, p->zmm_store));
    printf("      masked store: vmaskmovps %.1f cycles each against %.1f for a load, vblendvps "
           "and store of the\n"
           "      same bytes, so the kernels merge whole vectors and keep vmaskmovps for an "
           "array's tail\n",
           p->masked_store_cyc, p->merge_cyc);
    if (p->zmm_masked_store_cyc > 0)
        printf("      (opmask store of a zmm: %.1f cycles)\n", p->zmm_masked_store_cyc);
    if (!b->classified) printf("  resource bound: UNAVAILABLE: %s\n", b->class_error);
    else
        printf("    operations by class from objdump -d of this executable at the executed "
               "addresses (loads and\n"
               "    stores by operand, vector ops: xmm/ymm/zmm/k instructions but moves)\n");
}

static void print_counts(const bench_run *b)
{
    char buf[32];
    if (!b->opt.count || b->count_failed) return;
    printf("\ninstructions per vector iteration / issue bound in Mt/s\n");
    print_isa_header(b->isas, b->nisa, 16, "  instr   bound");
    for (size_t ci = 0; ci < NCASES; ci++) {
        print_row_label(&cases[ci]);
        for (size_t i = 0; i < b->nisa; i++) {
            const result *r = &b->res[ci][i];
            double bound = issue_bound(r, b->hz, b->width, lanes_isa_lanes(b->isas[i]));
            printf(" %6.1f %s", r->ipi, fmt_rate(buf, sizeof buf, bound));
        }
        printf("\n");
    }
    if (!b->classified || !b->pipes.measured) return;
    printf("\ncycles per vector iteration: measured / resource bound / the resource that sets "
           "it\n");
    print_isa_header(b->isas, b->nisa, 24, " cycles  bound by      ");
    for (size_t ci = 0; ci < NCASES; ci++) {
        print_row_label(&cases[ci]);
        for (size_t i = 0; i < b->nisa; i++) {
            const result *r = &b->res[ci][i];
            int which;
            double bound = resource_bound(r, b, &which);
            double cyc = measured_cycles(r, b->hz, lanes_isa_lanes(b->isas[i]));
            if (bound > 0)
                printf(" %7.1f %6.1f %-9s", cyc, bound, resource_name[which]);
            else
                printf(" %7.1f %6s %-9s", cyc, "n/a", "");
        }
        printf("\n");
    }
}

static void print_utilization(const bench_run *b)
{
    bool all_full = true;
    for (size_t ci = 0; ci < NCASES; ci++)
        for (size_t i = 0; i < b->nisa; i++)
            if (b->res[ci][i].utilization != 1.0) all_full = false;
    if (all_full) {
        printf("\nlane utilization (active lanes / lane slots, one counting run per kernel and "
               "set): 1.000 everywhere;\n"
               "  every call covers a multiple of 16 valid rays or primitives (frustum_build takes "
               "no stats: computed)\n");
        return;
    }
    printf("\nlane utilization (active lanes / lane slots, one counting run per kernel and set)\n");
    print_isa_header(b->isas, b->nisa, 10, "      util");
    for (size_t ci = 0; ci < NCASES; ci++) {
        print_row_label(&cases[ci]);
        for (size_t i = 0; i < b->nisa; i++) printf(" %9.3f", b->res[ci][i].utilization);
        printf("%s\n", cases[ci].counts_hits ? "" : "  (computed: the kernel takes no stats)");
    }
}

static void print_inputs(const bench_run *b)
{
    printf("\ninputs (hit or keep rates of the %s set; culls: share some ray really hits):\n",
           lanes_isa_name(b->isas[0]));
    for (size_t ci = 0; ci < NCASES; ci++) {
        const bench_case *c = &cases[ci];
        const result *r = &b->res[ci][0];
        printf("  %-22s %-6s %zu %s; %zu call%s per batch", c->kernel, c->form, c->n, c->what,
               c->calls, c->calls == 1 ? "" : "s");
        if (c->counts_hits)
            printf("; %.1f%% %s", 100.0 * (double)r->answer / (double)(c->calls * c->n),
                   c->truth != TRUTH_NONE ? "kept" : "hit");
        if (c->truth != TRUTH_NONE)
            printf(" (%.1f%% hit)", 100.0 * (double)b->needed_count[c->truth] / (double)c->n);
        printf("\n");
    }

    bool agree = true, conservative = true;
    for (size_t ci = 0; ci < NCASES; ci++)
        for (size_t i = 0; i < b->nisa; i++) {
            if (b->res[ci][i].answer != b->res[ci][0].answer) agree = false;
            if (b->res[ci][i].culled_hit) conservative = false;
        }
    if (agree) {
        printf("check: every set returned the same hit and keep counts and the same frustum\n");
    } else {
        printf("check: results DIFFER between sets (Moller may differ by FMA rounding; anything "
               "else is a bug):\n");
        for (size_t ci = 0; ci < NCASES; ci++) {
            bool same = true;
            for (size_t i = 1; i < b->nisa; i++)
                if (b->res[ci][i].answer != b->res[ci][0].answer) same = false;
            if (same) continue;
            printf("  %s/%s:", cases[ci].kernel, cases[ci].form);
            for (size_t i = 0; i < b->nisa; i++)
                printf(" %s=%llu", lanes_isa_name(b->isas[i]),
                       (unsigned long long)b->res[ci][i].answer);
            printf("\n");
        }
    }
    if (conservative) {
        printf("check: every culled primitive is missed by all rays of the packet (culls are "
               "conservative)\n");
    } else {
        printf("check: BUG: culls rejected primitives that a ray of the packet hits:\n");
        for (size_t ci = 0; ci < NCASES; ci++)
            for (size_t i = 0; i < b->nisa; i++)
                if (b->res[ci][i].culled_hit)
                    printf("  %s/%s %s: %zu of %zu hit primitives culled\n", cases[ci].kernel,
                           cases[ci].form, lanes_isa_name(b->isas[i]), b->res[ci][i].culled_hit,
                           b->needed_count[cases[ci].truth]);
    }
}

static void write_csv(const bench_run *b, FILE *csv)
{
    fprintf(csv, "kernel,form,isa,lanes,mtests_per_s,median_ns_per_test,instructions_per_iter,"
                 "bound_mtests_per_s,fraction_of_bound,lane_utilization,cycles_per_iter,"
                 "resource_bound_cycles,bound_resource\n");
    for (size_t ci = 0; ci < NCASES; ci++)
        for (size_t i = 0; i < b->nisa; i++) {
            const result *r = &b->res[ci][i];
            int lanes = lanes_isa_lanes(b->isas[i]);
            double bound = issue_bound(r, b->hz, b->width, lanes);
            cli_csv_field(csv, cases[ci].kernel);
            fputc(',', csv);
            cli_csv_field(csv, cases[ci].form);
            fputc(',', csv);
            cli_csv_field(csv, lanes_isa_name(b->isas[i]));
            fprintf(csv, ",%d,%.4f,%.5f,", lanes, mtests(r), r->ns_per_test);
            /* Empty fields where the count is unavailable: no invented numbers. */
            if (bound > 0)
                fprintf(csv, "%.2f,%.4f,%.4f,", r->ipi, bound, mtests(r) / bound);
            else
                fprintf(csv, ",,,");
            fprintf(csv, "%.4f,%.2f,", r->utilization, measured_cycles(r, b->hz, lanes));
            int which;
            double rb = resource_bound(r, b, &which);
            if (rb > 0)
                fprintf(csv, "%.2f,%s\n", rb, resource_name[which]);
            else
                fprintf(csv, ",\n");
        }
}

static void parse_options(cli_context *ctx, const cli_command *self, int argc, char **argv,
                          options *opt)
{
    bool reps_given = false, run_given = false;
    const char *v;
    *opt = (options){false, NULL, 0, 0, 0, false, true};
    cli_args a = cli_args_begin(ctx, self, argc, argv);
    while (cli_args_next(&a)) {
        if (cli_flag(&a, "--all"))
            opt->all = true;
        else if (cli_flag(&a, "--quick"))
            opt->quick = true;
        else if (cli_flag(&a, "--no-count"))
            opt->count = false;
        else if (cli_value(&a, "--csv", &v))
            opt->csv = v;
        else if (cli_value(&a, "--reps", &v))
            opt->reps = cli_parse_count(&a, "--reps", v, 1, 1000), reps_given = true;
        else if (cli_value(&a, "--run-ms", &v))
            opt->run_ms = cli_parse_count(&a, "--run-ms", v, 1, 10000), run_given = true;
        else if (cli_value(&a, "--issue-width", &v))
            opt->issue_width = cli_parse_count(&a, "--issue-width", v, 1, 64);
        else if (!cli_global_option(&a))
            cli_unknown_option(&a);
    }
    if (opt->all && ctx->forced_isa != LANES_ISA_NONE)
        cli_usage_error(ctx, self, "--isa and --all exclude each other");
    if (opt->csv && !opt->csv[0]) cli_usage_error(ctx, self, "--csv needs a file name");
    if (!reps_given) opt->reps = opt->quick ? 3 : 7;
    if (!run_given) opt->run_ms = opt->quick ? 3 : 25;
}

static int bench_kernels_run(cli_context *ctx, const cli_command *self, int argc, char **argv)
{
    static bench_run run; /* large: results of every kernel and set */
    bench_run *b = &run;
    memset(b, 0, sizeof *b);
    b->min_share = 1.0;
    parse_options(ctx, self, argc, argv, &b->opt);
    b->max_samples = b->opt.quick ? 2 : 4;
    b->budget = b->opt.quick ? 1500 : 8000;

    /* The sets to measure: --isa names one; otherwise all this CPU runs. */
    for (int i = 0; i < LANES_ISA_COUNT; i++) {
        lanes_isa isa = (lanes_isa)i;
        if (ctx->forced_isa != LANES_ISA_NONE && isa != ctx->forced_isa) continue;
        if (lanes_isa_supported(isa) && lanes_kernels_for(isa)) b->isas[b->nisa++] = isa;
    }
    if (b->nisa == 0) cli_fail("no instruction set to measure");

    /* Open the CSV now: a bad path should fail before a minute of measuring. */
    FILE *csv = NULL;
    if (b->opt.csv) {
        csv = cli_create_file("--csv", b->opt.csv);
    }

    char why[200];
    int cpu = pin_thread(why, sizeof why);
    if (cpu < 0) cli_warn("cannot pin the thread (%s); figures may mix cores", why);

    kernel_inputs *in = malloc(sizeof *in);
    outputs out;
    memset(&out, 0, sizeof out);
    size_t max_n = KI_WIDE_COUNT > KI_CULL_COUNT ? KI_WIDE_COUNT : KI_CULL_COUNT;
    if (max_n < KI_PACKET_RAYS) max_n = KI_PACKET_RAYS;
    size_t padded = (max_n + LANES_MAX_W - 1) / LANES_MAX_W * LANES_MAX_W;
    out.bits = aligned_alloc(LANES_ALIGN, lanes_mask_words(padded) * sizeof(uint32_t) + LANES_ALIGN);
    out.tentry = aligned_alloc(LANES_ALIGN, padded * sizeof(float));
    if (!in || !out.bits || !out.tentry || !lanes_tri_hits_alloc(&out.tri, padded) ||
        !kernel_inputs_make(in) || !make_truth(b, in))
        cli_fail("out of memory for the benchmark inputs");

    const lanes_cpu_features *cpuf = lanes_cpu();
    cli_cpu_signature sig = cli_cpu_signature_read();
    b->core = km_core_model(cpuf->vendor, sig.family, sig.model);
    b->width = b->opt.issue_width ? (int)b->opt.issue_width : b->core.issue_width;
    char reason[160];
    lanes_isa selected = lanes_isa_current();

    printf("lanes bench kernels\n");
    printf("cpu:       %s (%s, family 0x%x model 0x%x stepping %u)\n", cpuf->brand, cpuf->vendor,
           sig.family, sig.model, sig.stepping);
    printf("compiler:  %s\n", cli_compiler());
    printf("selected:  %s (%d lanes; %s)\n", lanes_isa_name(selected), lanes_isa_lanes(selected),
           cli_isa_selection_reason(ctx, reason, sizeof reason));
    printf("measured:  ");
    for (size_t i = 0; i < b->nisa; i++) printf("%s%s", i ? " " : "", lanes_isa_name(b->isas[i]));
    printf("\n");
    if (cpu >= 0)
        printf("thread:    1, pinned to CPU %d\n", cpu);
    else
        printf("thread:    1, not pinned\n");
    printf("timing:    median of %lu runs of ~%lu ms per kernel and set, sets interleaved; "
           "CLOCK_MONOTONIC; stats = NULL\n",
           b->opt.reps, b->opt.run_ms);
    fflush(stdout);

    bool progress = isatty(STDERR_FILENO);
    double clock_ms = b->opt.quick ? 3 : 15;
    b->hz_before = km_measure_clock_hz(7, clock_ms);
    for (size_t ci = 0; ci < NCASES; ci++) measure_case(b, ci, in, &out, progress);
    if (progress) fprintf(stderr, "\r\033[K");
    b->hz_after = km_measure_clock_hz(7, clock_ms);
    b->hz = 0.5 * (b->hz_before + b->hz_after);
    b->pipes = km_measure_pipes(b->hz, 7, b->opt.quick ? 2 : 10);
    if (b->opt.count && !b->count_failed) classify_all(b);

    printf("cpu share: %.1f%% (thread CPU time / wall time of timed runs, median per kernel and "
           "set; lowest shown)\n",
           100.0 * b->min_share);
    if (b->min_share < 0.95)
        cli_warn("the benchmark thread had only %.0f%% of its CPU during some timed runs: other "
                 "load on CPU %d disturbed the figures; rerun on a quiet machine",
                 100.0 * b->min_share, cpu);
    print_throughput(b);
    print_model(b);
    print_counts(b);
    print_utilization(b);
    print_inputs(b);
    if (csv) {
        write_csv(b, csv);
        cli_finish_file("--csv", b->opt.csv, csv);
        printf("\nwrote %s\n", b->opt.csv);
    }

    for (size_t ci = 0; ci < NCASES; ci++)
        for (size_t i = 0; i < b->nisa; i++) free(b->res[ci][i].sites[0]), free(b->res[ci][i].sites[1]);
    free(b->needed[TRUTH_BOXES]);
    free(b->needed[TRUTH_TRIS]);
    kernel_inputs_free(in);
    free(in);
    free(out.bits);
    free(out.tentry);
    lanes_tri_hits_free(&out.tri);
    return fflush(stdout) == 0 ? 0 : 1;
}

const cli_command cli_cmd_bench_kernels = {
    .name = "kernels",
    .summary = "throughput of the box, triangle and frustum kernels per instruction set",
    .usage =
        "usage: lanes bench kernels [--isa NAME | --all] [--csv FILE] [--reps N] [--quick]\n"
        "                           [--run-ms N] [--issue-width N] [--no-count]\n"
        "\n"
        "Single-threaded throughput (tests per second) of ray/box, ray/triangle (Moller and\n"
        "watertight) in packet form (N rays x 1 primitive) and wide form (1 ray x N\n"
        "primitives), frustum culling of boxes and triangles (interval and planes) and\n"
        "frustum building, as a fraction of a throughput bound from each kernel's\n"
        "instruction count and the core's issue width; and each kernel's cycles per\n"
        "vector iteration against a resource bound (its multiplies, adds, vector ops,\n"
        "loads, stores and masked stores over this core's rates for each, timed here),\n"
        "naming the resource that sets it.\n"
        "\n"
        "  --isa NAME         measure only NAME (default: every set this CPU runs; LANES_ISA\n"
        "                     changes the selected set shown, not the sets measured)\n"
        "  --all              every set this CPU runs (the default; excludes --isa)\n"
        "  --csv FILE         one row per kernel, form and set: kernel,form,isa,lanes,\n"
        "                     mtests_per_s,median_ns_per_test,instructions_per_iter,\n"
        "                     bound_mtests_per_s,fraction_of_bound,lane_utilization,\n"
        "                     cycles_per_iter,resource_bound_cycles,bound_resource\n"
        "  --reps N           timed runs per kernel and set, median reported (default 7; 1-1000)\n"
        "  --run-ms N         length of one timed run in ms (default 25; 1-10000)\n"
        "  --quick            smoke run: 3 runs of ~3 ms, fewer counted samples\n"
        "  --issue-width N    macro-ops per cycle for the bound (default: from the CPU model)\n"
        "  --no-count         skip instruction counting (bounds are then n/a)\n",
    .run = bench_kernels_run,
};
