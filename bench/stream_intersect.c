/* The path tracer's extension streams captured and traced again through
 * each intersection call (see stream_intersect.h). */
#include "bench/stream_intersect.h"

#include <lanes/lanes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench/cli_common.h"
#include "build/grow_array.h"
#include "trace/paths.h"
#include "trace/render.h"
#ifdef LANES_HAVE_COMPARE
#include "bench/embree_adapter.h"
#endif

/* The capture: an intersector around the set's own traversal that keeps
 * each call's rays (one render thread, so no lock). */
typedef struct {
    const lanes_kernels *k;
    const lanes_render_accel *accel;
    lanes_ray *rays;
    size_t count, capacity, limit;
    size_t *stream_end; /* stream i is rays [stream_end[i-1], stream_end[i]) */
    size_t streams, stream_capacity;
    bool out_of_memory;
} capture;

static void capture_trace(void *ctx, const lanes_ray *rays, size_t n, lanes_hit *hits)
{
    capture *c = ctx;
    c->k->trace_wide(&c->accel->wide, LANES_ACCURACY_DEFAULT, rays, n, hits, NULL);
    if (n == 0 || c->count + n > c->limit || c->out_of_memory) return;
    if (!lanes_grow_array((void **)&c->rays, &c->capacity, c->count + n, sizeof *c->rays) ||
        !lanes_grow_array((void **)&c->stream_end, &c->stream_capacity, c->streams + 1, sizeof *c->stream_end)) {
        c->out_of_memory = true;
        return;
    }
    memcpy(c->rays + c->count, rays, n * sizeof *rays);
    c->count += n;
    c->stream_end[c->streams++] = c->count;
}

static void capture_occluded(void *ctx, const lanes_ray *rays, size_t n, uint8_t *occluded)
{
    capture *c = ctx;
    c->k->occluded_wide(&c->accel->wide, LANES_ACCURACY_DEFAULT, rays, n, occluded, NULL);
}

/* ---- the calls raced ------------------------------------------------------ */

/* CALL_AOS_SETUP: the renderer's whole cost of a stream, its set-up (1/d
 * and the checks, which its generate stage does) with the trace. */
typedef enum { CALL_AOS, CALL_AOS_SETUP, CALL_SOA, CALL_EMBREE } call_kind;

typedef struct {
    call_kind kind;
    bool coherent;
#ifdef LANES_HAVE_COMPARE
    lanes_embree_batch batch;
#endif
    double seconds[64];
} call;

/* What every call traces: the captured streams, laid out for each. */
typedef struct {
    const capture *cap;
    lanes_accel public_accel;
    float *soa;         /* 8 arrays of count: ox oy oz dx dy dz tnear tfar */
    float *soa_hits;    /* t, u, v of count each */
    uint32_t *soa_prim;
    lanes_hit *hits;    /* the call being raced, as lanes_hit */
    lanes_ray *scratch; /* CALL_AOS_SETUP's rays, set up again each run */
#ifdef LANES_HAVE_COMPARE
    lanes_embree *embree;
#endif
} race;

static double run(race *r, call *c)
{
    const capture *cap = r->cap;
    size_t n = cap->count;
#ifdef LANES_HAVE_COMPARE
    if (c->kind == CALL_EMBREE) lanes_embree_batch_reset(&c->batch);
    unsigned csr = lanes_fp_fast_enter();
#endif
    double t = lanes_render_clock();
    for (size_t s = 0, begin = 0; s < cap->streams; begin = cap->stream_end[s++]) {
        size_t end = cap->stream_end[s], m = end - begin;
        if (c->kind == CALL_AOS) {
            cap->k->trace_wide(&cap->accel->wide, LANES_ACCURACY_DEFAULT, cap->rays + begin, m, r->hits + begin, NULL);
        } else if (c->kind == CALL_AOS_SETUP) {
            for (size_t i = begin; i < end; i++) {
                r->scratch[i] = cap->rays[i];
                lanes_ray_prepare_rcp(&r->scratch[i], LANES_RCP_EXACT);
            }
            cap->k->trace_wide(&cap->accel->wide, LANES_ACCURACY_DEFAULT, r->scratch + begin, m, r->hits + begin, NULL);
        } else if (c->kind == CALL_SOA) {
            lanes_rays_soa rays = {r->soa + begin,         r->soa + n + begin,     r->soa + 2 * n + begin,
                                   r->soa + 3 * n + begin, r->soa + 4 * n + begin, r->soa + 5 * n + begin,
                                   r->soa + 6 * n + begin, r->soa + 7 * n + begin};
            lanes_hits_soa hits = {r->soa_hits + begin, r->soa_hits + n + begin, r->soa_hits + 2 * n + begin,
                                   r->soa_prim + begin};
            if (lanes_intersect_stream(r->public_accel, &rays, m, &hits) != LANES_OK)
                cli_fail("study --paths: lanes_intersect_stream: %s", lanes_last_error_message());
        } else {
#ifdef LANES_HAVE_COMPARE
            /* packets take consecutive rays: one call over every stream,
             * so a packet straddles two streams at each boundary */
            int w = lanes_embree_method_width(c->batch.method);
            if (w > 1) {
                lanes_embree_batch_trace(r->embree, &c->batch, 0, n, c->coherent);
                break;
            }
            lanes_embree_batch_trace(r->embree, &c->batch, begin, end, c->coherent);
#endif
        }
    }
    t = lanes_render_clock() - t;
#ifdef LANES_HAVE_COMPARE
    lanes_fp_restore(csr);
#endif
    return t;
}

/* The raced call's answers as lanes_hit, for the comparison. */
static void answers(race *r, call *c, lanes_hit *out)
{
    size_t n = r->cap->count;
    if (c->kind == CALL_AOS || c->kind == CALL_AOS_SETUP) {
        memcpy(out, r->hits, n * sizeof *out);
    } else if (c->kind == CALL_SOA) {
        for (size_t i = 0; i < n; i++)
            out[i] = (lanes_hit){r->soa_hits[i], r->soa_hits[n + i], r->soa_hits[2 * n + i], r->soa_prim[i]};
    } else {
#ifdef LANES_HAVE_COMPARE
        lanes_embree_batch_hits(&c->batch, out);
#endif
    }
}

static bool same_hit(const lanes_hit *a, const lanes_hit *b)
{
    if (a->prim == LANES_NO_HIT || b->prim == LANES_NO_HIT) return a->prim == b->prim;
    return a->prim == b->prim && fabsf(a->t - b->t) <= 1e-4f * fabsf(b->t);
}

static void open_public_accel(race *r, const lanes_scene *scene, lanes_isa isa)
{
    char config[64];
    snprintf(config, sizeof config, "isa=%s,accuracy=default,threads=0", lanes_isa_name(isa));
    lanes_device d;
    if (lanes_device_create(config, &d) != LANES_OK) cli_fail("study --paths: %s", lanes_last_error_message());
    size_t nv = 3 * scene->triangle_count;
    uint32_t *index = malloc(nv * sizeof *index);
    if (!index) cli_fail("study --paths: out of memory");
    for (size_t i = 0; i < nv; i++) index[i] = (uint32_t)i;
    if (lanes_accel_create(d, scene->verts, nv, index, scene->triangle_count, &r->public_accel) != LANES_OK)
        cli_fail("study --paths: %s", lanes_last_error_message());
    free(index);
    lanes_device_release(d);
}

static void lay_out_soa(race *r)
{
    const capture *cap = r->cap;
    size_t n = cap->count;
    r->soa = malloc(8 * n * sizeof *r->soa);
    r->soa_hits = malloc(3 * n * sizeof *r->soa_hits);
    r->soa_prim = malloc(n * sizeof *r->soa_prim);
    r->hits = malloc(n * sizeof *r->hits);
    r->scratch = malloc(n * sizeof *r->scratch);
    if (!r->soa || !r->soa_hits || !r->soa_prim || !r->hits || !r->scratch)
        cli_fail("study --paths: out of memory for %zu rays", n);
    for (size_t i = 0; i < n; i++) {
        const lanes_ray *ray = &cap->rays[i];
        for (int k = 0; k < 3; k++) r->soa[(size_t)k * n + i] = ray->o[k], r->soa[(size_t)(3 + k) * n + i] = ray->d[k];
        r->soa[6 * n + i] = ray->tnear, r->soa[7 * n + i] = ray->tfar;
    }
}

void lanes_stream_intersect_measure(const lanes_scene *scene, const lanes_render_accel *accel, lanes_isa isa, int width,
                                    int height, int spp, int stream, int reps, size_t max_rays,
                                    stream_intersect_result *out)
{
    memset(out, 0, sizeof *out);
    const lanes_kernels *k = lanes_kernels_for(isa);
    lanes_error err;
    capture cap = {k, accel, NULL, 0, 0, max_rays, NULL, 0, 0, false};
    lanes_paths_intersector x = {"capture", &cap, capture_trace, capture_occluded};
    lanes_paths_options po;
    lanes_paths_default_options(&po);
    po.isa = isa, po.method = LANES_PATHS_STREAM, po.accuracy = LANES_ACCURACY_DEFAULT;
    po.width = width, po.height = height, po.spp = spp, po.stream = stream, po.threads = 1;
    po.intersector = &x;
    lanes_paths_result res;
    if (lanes_paths_render(scene, accel, &po, &res, &err) != LANES_OK) cli_fail("study --paths: %s", err.message);
    lanes_paths_result_free(&res);
    if (cap.out_of_memory) cli_fail("study --paths: out of memory capturing the streams");
    out->rays = cap.count, out->streams = cap.streams;

    race r = {&cap, NULL, NULL, NULL, NULL, NULL, NULL
#ifdef LANES_HAVE_COMPARE
              , NULL
#endif
    };
    open_public_accel(&r, scene, isa);
    lay_out_soa(&r);
    call calls[STREAM_INTERSECT_MAX_APIS];
    int ncalls = 0;
    calls[ncalls++] = (call){.kind = CALL_AOS};
    snprintf(out->api[0].name, sizeof out->api[0].name, "trace_wide (AoS)");
    calls[ncalls++] = (call){.kind = CALL_SOA};
    snprintf(out->api[1].name, sizeof out->api[1].name, "lanes_intersect_stream (SoA)");
    calls[ncalls++] = (call){.kind = CALL_AOS_SETUP};
    snprintf(out->api[2].name, sizeof out->api[2].name, "set-up + trace_wide (AoS)");
#ifdef LANES_HAVE_COMPARE
    if (lanes_embree_create(scene, lanes_embree_isa_best(), 0, &r.embree, &err) != LANES_OK)
        cli_fail("study --paths: %s", err.message);
    snprintf(out->embree_isa, sizeof out->embree_isa, "%s", lanes_embree_isa_name(lanes_embree_get_isa(r.embree)));
    const lanes_embree_method methods[] = {LANES_EMBREE_1, LANES_EMBREE_8, LANES_EMBREE_16, LANES_EMBREE_1M, LANES_EMBREE_NP};
    for (size_t m = 0; m < sizeof methods / sizeof methods[0]; m++) {
        if (!lanes_embree_supports(r.embree, methods[m])) continue;
        for (int coherent = 0; coherent < 2; coherent++) {
            if (coherent && methods[m] == LANES_EMBREE_1) continue; /* a single ray has no coherence to use */
            call *c = &calls[ncalls];
            *c = (call){.kind = CALL_EMBREE, .coherent = coherent != 0};
            if (lanes_embree_batch_init(&c->batch, methods[m], false, cap.rays, cap.count, &err) != LANES_OK)
                cli_fail("study --paths: %s", err.message);
            stream_intersect_api *a = &out->api[ncalls++];
            snprintf(a->name, sizeof a->name, "%s%s", lanes_embree_method_name(methods[m], false),
                     coherent ? "+coherent" : "");
            a->embree = true;
        }
    }
#endif
    if (reps > 64) reps = 64;
    /* one untimed run each: the output arrays' first touch (page faults)
     * and the caches' first fill fall outside the clock */
    for (int i = 0; i < ncalls; i++) run(&r, &calls[i]);
    for (int round = 0; round < reps; round++)
        for (int i = 0; i < ncalls; i++) calls[i].seconds[round] = run(&r, &calls[i]);
    lanes_hit *reference = malloc(cap.count * sizeof *reference), *got = malloc(cap.count * sizeof *got);
    if (!reference || !got) cli_fail("study --paths: out of memory for %zu hits", cap.count);
    run(&r, &calls[0]);
    answers(&r, &calls[0], reference);
    for (int i = 0; i < ncalls; i++) {
        run(&r, &calls[i]); /* the two AoS calls share their hits array */
        answers(&r, &calls[i], got);
        for (size_t j = 0; j < cap.count; j++) out->api[i].differ += !same_hit(&got[j], &reference[j]);
        double s = cli_median(calls[i].seconds, (size_t)reps);
        out->api[i].mrays = s > 0.0 ? (double)cap.count / s * 1e-6 : 0.0;
#ifdef LANES_HAVE_COMPARE
        if (calls[i].kind == CALL_EMBREE) lanes_embree_batch_free(&calls[i].batch);
#endif
    }
    out->apis = ncalls;
    free(reference), free(got);
#ifdef LANES_HAVE_COMPARE
    lanes_embree_destroy(r.embree);
#endif
    lanes_accel_release(r.public_accel);
    free(r.soa), free(r.soa_hits), free(r.soa_prim), free(r.hits), free(r.scratch);
    free(cap.rays), free(cap.stream_end);
}
