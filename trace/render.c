/* The Whitted renderer (see render.h). One ray at a time through the kernel
 * table of the chosen set; threads take 16x16 tiles from a shared counter. */
#define _DEFAULT_SOURCE /* clock_gettime */
#include "trace/render.h"

#include "build/camera.h"
#include "build/parallel.h"
#include "trace/scene_plan.h"
#include "trace/shading.h"

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const scheme_names[LANES_SCHEME_COUNT] = {"single", "wide"};

const char *lanes_scheme_name(lanes_scheme s)
{
    return s >= 0 && s < LANES_SCHEME_COUNT ? scheme_names[s] : "?";
}

int lanes_scheme_from_name(const char *name)
{
    for (int i = 0; name && i < LANES_SCHEME_COUNT; i++)
        if (strcmp(name, scheme_names[i]) == 0) return i;
    return -1;
}

void lanes_render_default_options(lanes_render_options *o)
{
    memset(o, 0, sizeof *o);
    o->isa = lanes_isa_current();
    o->scheme = LANES_SCHEME_WIDE;
    o->accuracy = LANES_ACCURACY_FROM_SCENE;
    o->width = 0; /* the scene camera's size */
    o->height = 0;
    o->spp = 1;
    o->max_depth = 10;
    o->area_samples = 4;
}

lanes_status lanes_render_accel_build(const lanes_scene *scene, const lanes_kernels *wide_for, bool bvh2,
                                      int threads, lanes_render_accel *a, lanes_error *err)
{
    lanes_status status = LANES_OK;
    lanes_bvh_build_options bo;
    memset(a, 0, sizeof *a);
    if (!wide_for && !bvh2) return lanes_error_set(err, LANES_ERR_BAD_INPUT, "render accel: nothing to build");
    lanes_bvh_default_options(&bo);
    bo.threads = threads;
    if (bvh2) status = lanes_bvh2_build(scene, &bo, &a->bvh2, err);
    if (status == LANES_OK && wide_for) status = lanes_wbvh_build(scene, wide_for->wide_width, &bo, &a->wide, err);
    if (status != LANES_OK) lanes_render_accel_free(a);
    return status;
}

void lanes_render_accel_free(lanes_render_accel *a)
{
    lanes_bvh2_free(&a->bvh2);
    if (a->wide.width) lanes_wbvh_free(&a->wide);
    memset(a, 0, sizeof *a);
}

/* Per-thread state: counters are summed when the threads finish. */
typedef struct {
    const lanes_scene *scene;
    const lanes_render_accel *accel;
    const lanes_render_options *opt; /* = &resolved */
    lanes_render_options resolved;   /* the caller's, with the accuracy mode resolved */
    const lanes_kernels *k;
    float eps;          /* offset of secondary origins, scaled to the scene */
    lanes_rcp_mode rcp; /* of the accuracy mode */
    lanes_scene_plan plan;
    lanes_view view;
    float *rgb;
    int width, height, tiles_x, tiles_y;
    atomic_int tiles_done;
    pthread_mutex_t progress_lock;
} render_job;

typedef struct {
    uint64_t camera, shadow, secondary;
    uint64_t by_depth[LANES_MAX_DEPTH + 1];
    lanes_trace_stats traversal; /* with opt->count */
} ray_counts;

static lanes_hit trace(const render_job *job, vec3 o, vec3 d, float tnear, float tfar, ray_counts *count)
{
    if (job->opt->api_accel) {
        lanes_ray1 q = {{o.x, o.y, o.z}, {d.x, d.y, d.z}, tnear, tfar};
        lanes_hit1 h1;
        lanes_intersect1(job->opt->api_accel, &q, &h1);
        _Static_assert(LANES_INVALID_ID == LANES_NO_HIT, "a miss is the same id in both");
        lanes_hit h = {h1.t, h1.u, h1.v, h1.prim_id};
        return h;
    }
    lanes_ray r = {{o.x, o.y, o.z}, {d.x, d.y, d.z}, {0, 0, 0}, tnear, tfar};
    lanes_hit h;
    lanes_trace_stats *stats = job->opt->count ? &count->traversal : NULL;
    lanes_ray_prepare_rcp(&r, job->rcp);
    if (job->opt->scheme == LANES_SCHEME_WIDE)
        job->k->trace_wide(&job->accel->wide, job->opt->accuracy, &r, 1, &h, stats);
    else
        job->k->trace_bvh2(&job->accel->bvh2, job->opt->accuracy, &r, 1, &h, stats);
    return h;
}

static bool occluded(const render_job *job, vec3 o, vec3 d, float tfar, ray_counts *count)
{
    if (job->opt->api_accel) {
        lanes_ray1 q = {{o.x, o.y, o.z}, {d.x, d.y, d.z}, 0.0f, tfar};
        bool hit = false;
        lanes_occluded1(job->opt->api_accel, &q, &hit);
        return hit;
    }
    lanes_ray r = {{o.x, o.y, o.z}, {d.x, d.y, d.z}, {0, 0, 0}, 0.0f, tfar};
    uint8_t hit = 0;
    lanes_trace_stats *stats = job->opt->count ? &count->traversal : NULL;
    lanes_ray_prepare_rcp(&r, job->rcp);
    if (job->opt->scheme == LANES_SCHEME_WIDE)
        job->k->occluded_wide(&job->accel->wide, job->opt->accuracy, &r, 1, &hit, stats);
    else
        job->k->occluded_bvh2(&job->accel->bvh2, job->opt->accuracy, &r, 1, &hit, stats);
    return hit != 0;
}

/* Radiance carried back along o + t d, times weight. */
static vec3 shade(const render_job *job, vec3 o, vec3 d, vec3 weight, int depth, uint32_t seed,
                  lanes_shadow_ray *shadow, ray_counts *count)
{
    const lanes_scene *s = job->scene;
    lanes_hit h = trace(job, o, d, 0.0f, INFINITY, count);
    if (h.prim == LANES_NO_HIT) return v3_mul(weight, lanes_background(d));
    lanes_surface sf = job->plan.hit_geometry ? lanes_surface_at(s, &h, d) : lanes_surface_material(s, &h);
    switch (lanes_material_whitted_kind(sf.m->kind)) {
    case LANES_MAT_EMISSIVE:
        return v3_mul(weight, v3_load(sf.m->emission));
    case LANES_MAT_DIFFUSE: {
        vec3 sum;
        int n = lanes_diffuse_light(s, &sf, weight, seed, job->opt->accuracy, job->eps, job->opt->area_samples, shadow, &sum);
        sum = v3_add(sum, v3_mul(weight, v3_load(sf.m->emission)));
        for (int i = 0; i < n; i++) {
            count->shadow++;
            if (!occluded(job, shadow[i].o, shadow[i].d, shadow[i].tfar, count)) sum = v3_add(sum, shadow[i].add);
        }
        return sum;
    }
    case LANES_MAT_MIRROR:
    case LANES_MAT_GLASS: {
        if (depth >= job->opt->max_depth) return v3(0, 0, 0);
        lanes_bounce_ray b[2];
        int n = lanes_specular_rays(&sf, d, weight, seed, job->opt->accuracy, job->eps, b);
        vec3 sum = v3(0, 0, 0);
        for (int i = 0; i < n; i++) {
            count->secondary++;
            count->by_depth[depth + 1]++;
            sum = v3_add(sum, shade(job, b[i].o, b[i].d, b[i].weight, depth + 1, b[i].seed, shadow, count));
        }
        return sum;
    }
    case LANES_MAT_CONDUCTOR:
    case LANES_MAT_PLASTIC:
        break; /* not a Whitted kind: lanes_material_whitted_kind maps them */
    }
    return v3(0, 0, 0);
}

static void render_tile(render_job *job, int tile, lanes_shadow_ray *shadow, ray_counts *count)
{
    const lanes_render_options *opt = job->opt;
    int x0 = (tile % job->tiles_x) * 16, y0 = (tile / job->tiles_x) * 16;
    int strata = (int)ceilf(sqrtf((float)opt->spp));
    for (int y = y0; y < y0 + 16 && y < job->height; y++) {
        for (int x = x0; x < x0 + 16 && x < job->width; x++) {
            vec3 sum = v3(0, 0, 0);
            for (int s = 0; s < opt->spp; s++) {
                uint32_t seed = ((uint32_t)y * 65536u + (uint32_t)x) * 64u + (uint32_t)s;
                float sx = 0.5f, sy = 0.5f;
                if (opt->spp > 1) {
                    sx = ((float)(s % strata) + lanes_hash01(seed, 1, 0)) / (float)strata;
                    sy = ((float)(s / strata % strata) + lanes_hash01(seed, 2, 0)) / (float)strata;
                }
                vec3 d = lanes_view_dir(&job->view, (float)x + sx, (float)y + sy);
                count->camera++;
                sum = v3_add(sum, shade(job, job->view.eye, d, v3(1, 1, 1), 0, seed, shadow, count));
            }
            float *out = job->rgb + ((size_t)y * (size_t)job->width + (size_t)x) * 3;
            out[0] = sum.x / (float)opt->spp;
            out[1] = sum.y / (float)opt->spp;
            out[2] = sum.z / (float)opt->spp;
        }
    }
}

/* One worker's own state: its counts and room for one diffuse hit's shadow
 * rays. */
typedef struct {
    ray_counts count;
    lanes_shadow_ray *shadow;
} worker_state;

typedef struct {
    render_job *job;
    worker_state *workers;
} render_loop;

static void tile_task(void *ctx, size_t tile, int worker)
{
    render_loop *loop = ctx;
    render_job *job = loop->job;
    worker_state *w = &loop->workers[worker];
    render_tile(job, (int)tile, w->shadow, &w->count);
    int done = atomic_fetch_add(&job->tiles_done, 1) + 1;
    if (job->opt->progress) {
        pthread_mutex_lock(&job->progress_lock);
        job->opt->progress(job->opt->progress_ctx, (double)done / (double)(job->tiles_x * job->tiles_y));
        pthread_mutex_unlock(&job->progress_lock);
    }
}

lanes_status lanes_render_api_accel_create(const lanes_scene *scene, lanes_device device,
                                           lanes_accel *accel)
{
    /* The scene's triangles are unindexed: vertex j of triangle t is 3t + j. */
    size_t n = scene->triangle_count;
    uint32_t *idx = n <= UINT32_MAX / 3 ? malloc(3 * n * sizeof *idx + 1) : NULL;
    if (!idx) {
        *accel = NULL;
        return LANES_ERR_OUT_OF_MEMORY;
    }
    for (size_t i = 0; i < 3 * n; i++) idx[i] = (uint32_t)i;
    lanes_status st = lanes_accel_create(device, scene->verts, 3 * n, idx, n, accel);
    free(idx);
    return st;
}

double lanes_render_clock(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

lanes_status lanes_render(const lanes_scene *scene, const lanes_render_accel *accel,
                          const lanes_render_options *opt, lanes_render_result *out, lanes_error *err)
{
    memset(out, 0, sizeof *out);
    render_job job;
    memset(&job, 0, sizeof job);
    job.scene = scene;
    job.accel = accel;
    job.opt = opt;
    job.k = lanes_kernels_for(opt->isa);
    if (!job.k || !lanes_isa_supported(opt->isa)) {
        return lanes_error_set(err, job.k ? LANES_ERR_CPU_LACKS : LANES_ERR_NOT_COMPILED,
                               "render: instruction set '%s' is not available", lanes_isa_name(opt->isa));
    }
    if (opt->node_width) {
        const lanes_kernels *k = lanes_kernels_for_width(opt->isa, opt->node_width);
        if (!k)
            return lanes_error_set(err, LANES_ERR_BAD_INPUT, "render: the %s set has no kernels for %d-wide nodes",
                                   job.k->name, opt->node_width);
        job.k = k;
    }
    if (opt->api_accel && opt->scheme != LANES_SCHEME_WIDE) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT,
                               "render: the public API traces the wide scheme only");
    } else if (!opt->api_accel && opt->scheme == LANES_SCHEME_WIDE && accel->wide.width != job.k->wide_width) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT,
                               "render: the wide scheme at %s needs a %d-wide BVH (have %d)", job.k->name,
                               job.k->wide_width, accel->wide.width);
    } else if (!opt->api_accel && opt->scheme == LANES_SCHEME_SINGLE && accel->bvh2.node_count == 0) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "render: the single scheme needs the BVH2 (not built)");
    }
    job.width = opt->width > 0 ? opt->width : scene->camera.width;
    job.height = opt->height > 0 ? opt->height : scene->camera.height;
    if (job.width <= 0 || job.height <= 0 || job.width > LANES_CAMERA_MAX_SIDE || job.height > LANES_CAMERA_MAX_SIDE ||
        opt->spp < 1 || opt->spp > 65536 || opt->max_depth < 0 || opt->max_depth > LANES_MAX_DEPTH) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT,
                               "render: image size %dx%d, %d samples per pixel or depth %d out of range "
                               "(1..%d, 1..65536, 0..%d)",
                               job.width, job.height, opt->spp, opt->max_depth, LANES_CAMERA_MAX_SIDE,
                               LANES_MAX_DEPTH);
    }
    if (opt->accuracy < LANES_ACCURACY_FROM_SCENE || opt->accuracy >= LANES_ACCURACY_COUNT) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "render: accuracy mode %d unknown",
                               (int)opt->accuracy);
    }
    lanes_scene_plan_make(scene, opt->accuracy, &job.plan);
    lanes_status fits = lanes_scene_plan_check(&job.plan, err);
    if (fits != LANES_OK) return fits;
    job.resolved = *opt;
    job.resolved.accuracy = job.plan.accuracy;
    job.opt = &job.resolved;
    job.eps = lanes_scene_epsilon(scene);
    job.rcp = lanes_accuracy_precision(job.plan.accuracy).rcp;
    if (opt->api_accel) {
        lanes_accel_info ai;
        lanes_accel_get_info(opt->api_accel, &ai);
        if (strcmp(ai.isa, lanes_isa_name(opt->isa)) != 0 ||
            strcmp(ai.accuracy, lanes_accuracy_name(job.plan.accuracy)) != 0) {
            return lanes_error_set(
                err, LANES_ERR_BAD_INPUT,
                "render: the accel traces with %s in %s mode, the render asks for %s in %s mode", ai.isa,
                ai.accuracy, lanes_isa_name(opt->isa), lanes_accuracy_name(job.plan.accuracy));
        }
    }

    job.view = lanes_view_make(&scene->camera, job.width, job.height);

    job.rgb = calloc((size_t)job.width * (size_t)job.height * 3, sizeof(float));
    if (!job.rgb) {
        return lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY, "render: out of memory for the image");
    }
    job.tiles_x = (job.width + 15) / 16;
    job.tiles_y = (job.height + 15) / 16;
    pthread_mutex_init(&job.progress_lock, NULL);

    int threads = lanes_parallel_threads(opt->threads);
    worker_state *workers = calloc((size_t)threads, sizeof *workers);
    size_t shadow_room = (size_t)lanes_max_shadow_rays(scene, opt->area_samples) + 1;
    bool ok = workers != NULL;
    for (int i = 0; ok && i < threads; i++) {
        workers[i].shadow = calloc(shadow_room, sizeof(lanes_shadow_ray));
        ok = workers[i].shadow != NULL;
    }
    if (!ok) {
        for (int i = 0; workers && i < threads; i++) free(workers[i].shadow);
        free(workers);
        free(job.rgb);
        pthread_mutex_destroy(&job.progress_lock);
        return lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY, "render: out of memory");
    }
    double t0 = lanes_render_clock();
    render_loop loop = {&job, workers};
    lanes_parallel_for(threads, (size_t)job.tiles_x * (size_t)job.tiles_y, tile_task, &loop);
    out->seconds = lanes_render_clock() - t0;
    pthread_mutex_destroy(&job.progress_lock);

    for (int i = 0; i < threads; i++) {
        free(workers[i].shadow);
        out->camera_rays += workers[i].count.camera;
        out->shadow_rays += workers[i].count.shadow;
        out->secondary_rays += workers[i].count.secondary;
        for (int d = 0; d <= LANES_MAX_DEPTH; d++) out->secondary_by_depth[d] += workers[i].count.by_depth[d];
        lanes_trace_stats_add(&out->stats, &workers[i].count.traversal);
    }
    free(workers);
    out->rays = out->camera_rays + out->shadow_rays + out->secondary_rays;
    out->rgb = job.rgb;
    out->width = job.width;
    out->height = job.height;
    return LANES_OK;
}

void lanes_render_result_free(lanes_render_result *r)
{
    free(r->rgb);
    memset(r, 0, sizeof *r);
}
