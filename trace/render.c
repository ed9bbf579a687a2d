/* The Whitted renderer (see render.h). One ray at a time through the kernel
 * table of the chosen set; threads take 16x16 tiles from a shared counter. */
#define _DEFAULT_SOURCE /* sysconf(_SC_NPROCESSORS_ONLN), clock_gettime */
#include "trace/render.h"

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

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
    o->algo = LANES_TRI_MOLLER;
    o->width = 0; /* the scene camera's size */
    o->height = 0;
    o->spp = 1;
    o->max_depth = 10;
    o->area_samples = 4;
}

bool lanes_accel_build(const lanes_scene *scene, int wide_width, int threads, lanes_accel *a,
                       lanes_error *err)
{
    lanes_bvh_build_options bo;
    memset(a, 0, sizeof *a);
    lanes_bvh_default_options(&bo);
    bo.threads = threads;
    if (!lanes_bvh2_build(scene, &bo, &a->bvh2, err)) return false;
    if (wide_width > 0 && !lanes_wbvh_from_bvh2(&a->bvh2, wide_width, &a->wide, err)) {
        lanes_bvh2_free(&a->bvh2);
        return false;
    }
    return true;
}

void lanes_accel_free(lanes_accel *a)
{
    lanes_bvh2_free(&a->bvh2);
    if (a->wide.width) lanes_wbvh_free(&a->wide);
    memset(a, 0, sizeof *a);
}

#define LANES_PI 3.14159265358979323846f

typedef struct {
    float x, y, z;
} vec3;

static vec3 v3(float x, float y, float z) { return (vec3){x, y, z}; }
static vec3 v3_load(const float *p) { return (vec3){p[0], p[1], p[2]}; }
static vec3 add(vec3 a, vec3 b) { return v3(a.x + b.x, a.y + b.y, a.z + b.z); }
static vec3 sub(vec3 a, vec3 b) { return v3(a.x - b.x, a.y - b.y, a.z - b.z); }
static vec3 scale(vec3 a, float s) { return v3(a.x * s, a.y * s, a.z * s); }
static vec3 mul(vec3 a, vec3 b) { return v3(a.x * b.x, a.y * b.y, a.z * b.z); }
static float dot(vec3 a, vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static vec3 cross(vec3 a, vec3 b)
{
    return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static vec3 normalize(vec3 a)
{
    float l = sqrtf(dot(a, a));
    return l > 0.0f ? scale(a, 1.0f / l) : a;
}

/* Per-thread state: counters are summed when the threads finish. */
typedef struct {
    const lanes_scene *scene;
    const lanes_accel *accel;
    const lanes_render_options *opt;
    const lanes_kernels *k;
    float eps;          /* offset of secondary origins, scaled to the scene */
    vec3 cam_eye, cam_fwd, cam_right, cam_up;
    float *rgb;
    int width, height, tiles_x, tiles_y;
    atomic_int next_tile;
    atomic_int tiles_done;
    pthread_mutex_t progress_lock;
} render_job;

typedef struct {
    uint64_t camera, shadow, secondary;
} ray_counts;

static lanes_hit trace(const render_job *job, vec3 o, vec3 d, float tnear, float tfar)
{
    lanes_ray r = {{o.x, o.y, o.z}, {d.x, d.y, d.z}, {0, 0, 0}, tnear, tfar};
    lanes_hit h;
    lanes_ray_prepare(&r);
    if (job->opt->scheme == LANES_SCHEME_WIDE)
        job->k->trace_wide(&job->accel->wide, &job->accel->bvh2, job->opt->algo, &r, 1, &h, NULL);
    else
        job->k->trace_bvh2(&job->accel->bvh2, job->opt->algo, &r, 1, &h, NULL);
    return h;
}

static bool occluded(const render_job *job, vec3 o, vec3 d, float tfar)
{
    lanes_ray r = {{o.x, o.y, o.z}, {d.x, d.y, d.z}, {0, 0, 0}, 0.0f, tfar};
    uint8_t hit = 0;
    lanes_ray_prepare(&r);
    if (job->opt->scheme == LANES_SCHEME_WIDE)
        job->k->occluded_wide(&job->accel->wide, &job->accel->bvh2, job->opt->algo, &r, 1, &hit, NULL);
    else
        job->k->occluded_bvh2(&job->accel->bvh2, job->opt->algo, &r, 1, &hit, NULL);
    return hit != 0;
}

/* Deterministic per-sample numbers in [0,1): a hash, so images do not depend
 * on thread scheduling. */
static float hash01(uint32_t a, uint32_t b, uint32_t c)
{
    uint64_t x = ((uint64_t)a * 0x9E3779B97F4A7C15ull) ^ ((uint64_t)b << 32) ^ c;
    x ^= x >> 30;
    x *= 0xBF58476D1CE4E5B9ull;
    x ^= x >> 27;
    x *= 0x94D049BB133111EBull;
    x ^= x >> 31;
    return (float)(x >> 40) * 0x1p-24f;
}

static vec3 background(vec3 d)
{
    float t = 0.5f * (normalize(d).y + 1.0f);
    return add(scale(v3(0.05f, 0.05f, 0.06f), 1.0f - t), scale(v3(0.15f, 0.18f, 0.25f), t));
}

static vec3 reflect(vec3 d, vec3 n) { return sub(d, scale(n, 2.0f * dot(d, n))); }

/* Direct light at a diffuse point p with facing normal n. */
static vec3 direct_light(const render_job *job, vec3 p, vec3 n, vec3 albedo, uint32_t seed,
                         ray_counts *count)
{
    const lanes_scene *s = job->scene;
    vec3 sum = scale(albedo, 0.03f); /* a little ambient, so unlit parts are not black */
    vec3 origin = add(p, scale(n, job->eps));
    for (size_t i = 0; i < s->point_light_count; i++) {
        vec3 to = sub(v3_load(s->point_lights[i].position), origin);
        float dist2 = dot(to, to), dist = sqrtf(dist2);
        if (!(dist > 0.0f)) continue;
        vec3 l = scale(to, 1.0f / dist);
        float cosine = dot(n, l);
        if (cosine <= 0.0f) continue;
        count->shadow++;
        if (occluded(job, origin, l, dist * (1.0f - 1e-4f))) continue;
        vec3 in = scale(v3_load(s->point_lights[i].intensity), cosine / dist2);
        sum = add(sum, scale(mul(albedo, in), 1.0f / LANES_PI));
    }
    int ns = job->opt->area_samples;
    for (size_t i = 0; i < s->area_light_count && ns > 0; i++) {
        const lanes_area_light *al = &s->area_lights[i];
        vec3 eu = v3_load(al->edge_u), ev = v3_load(al->edge_v);
        vec3 ln = cross(eu, ev);
        float area = sqrtf(dot(ln, ln));
        if (!(area > 0.0f)) continue;
        ln = scale(ln, 1.0f / area);
        vec3 acc = v3(0, 0, 0);
        for (int k = 0; k < ns; k++) {
            float a = hash01(seed, (uint32_t)(2 * k), (uint32_t)i), b = hash01(seed, (uint32_t)(2 * k + 1), (uint32_t)i);
            vec3 q = add(v3_load(al->corner), add(scale(eu, a), scale(ev, b)));
            vec3 to = sub(q, origin);
            float dist2 = dot(to, to), dist = sqrtf(dist2);
            if (!(dist > 0.0f)) continue;
            vec3 l = scale(to, 1.0f / dist);
            float cos_p = dot(n, l), cos_l = -dot(ln, l);
            if (cos_p <= 0.0f || cos_l <= 0.0f) continue;
            count->shadow++;
            if (occluded(job, origin, l, dist * (1.0f - 1e-4f))) continue;
            acc = add(acc, scale(v3_load(al->emission), cos_p * cos_l * area / dist2));
        }
        sum = add(sum, scale(mul(albedo, acc), 1.0f / (LANES_PI * (float)ns)));
    }
    return sum;
}

static vec3 shade(const render_job *job, vec3 o, vec3 d, float tnear, int depth, uint32_t seed,
                  ray_counts *count)
{
    const lanes_scene *s = job->scene;
    lanes_hit h = trace(job, o, d, tnear, INFINITY);
    if (h.prim == LANES_NO_HIT) return background(d);

    const float *v = s->verts + (size_t)h.prim * 9;
    vec3 v0 = v3_load(v), e1 = sub(v3_load(v + 3), v0), e2 = sub(v3_load(v + 6), v0);
    vec3 p = add(v0, add(scale(e1, h.u), scale(e2, h.v)));
    vec3 n = normalize(cross(e1, e2));
    bool front = dot(n, d) < 0.0f;
    vec3 nf = front ? n : scale(n, -1.0f);
    const lanes_material *m = &s->materials[s->material_of[h.prim]];
    vec3 color = v3_load(m->color);

    switch (m->kind) {
    case LANES_MAT_EMISSIVE:
        return v3_load(m->emission);
    case LANES_MAT_DIFFUSE:
        return direct_light(job, p, nf, color, seed, count);
    case LANES_MAT_MIRROR:
        if (depth >= job->opt->max_depth) return v3(0, 0, 0);
        count->secondary++;
        return mul(color, shade(job, add(p, scale(nf, job->eps)), reflect(d, nf), 0.0f, depth + 1,
                                seed * 31u + 7u, count));
    case LANES_MAT_GLASS: {
        if (depth >= job->opt->max_depth) return v3(0, 0, 0);
        vec3 dn = normalize(d);
        float eta = front ? 1.0f / m->ior : m->ior;
        float cosi = -dot(dn, nf);
        float k = 1.0f - eta * eta * (1.0f - cosi * cosi);
        vec3 refl_dir = reflect(dn, nf);
        count->secondary++;
        vec3 refl = shade(job, add(p, scale(nf, job->eps)), refl_dir, 0.0f, depth + 1,
                          seed * 31u + 11u, count);
        if (k < 0.0f) return mul(color, refl); /* total internal reflection */
        float r0 = (1.0f - m->ior) / (1.0f + m->ior);
        r0 *= r0;
        float fresnel = r0 + (1.0f - r0) * powf(1.0f - cosi, 5.0f);
        vec3 refr_dir = add(scale(dn, eta), scale(nf, eta * cosi - sqrtf(k)));
        count->secondary++;
        vec3 refr = shade(job, sub(p, scale(nf, job->eps)), refr_dir, 0.0f, depth + 1,
                          seed * 31u + 13u, count);
        return mul(color, add(scale(refl, fresnel), scale(refr, 1.0f - fresnel)));
    }
    }
    return v3(0, 0, 0);
}

static void render_tile(render_job *job, int tile, ray_counts *count)
{
    const lanes_render_options *opt = job->opt;
    int x0 = (tile % job->tiles_x) * 16, y0 = (tile / job->tiles_x) * 16;
    float aspect = (float)job->width / (float)job->height;
    float tan_half = tanf(job->scene->camera.fov_y_degrees * LANES_PI / 360.0f);
    int strata = (int)ceilf(sqrtf((float)opt->spp));
    for (int y = y0; y < y0 + 16 && y < job->height; y++) {
        for (int x = x0; x < x0 + 16 && x < job->width; x++) {
            vec3 sum = v3(0, 0, 0);
            for (int s = 0; s < opt->spp; s++) {
                uint32_t seed = ((uint32_t)y * 65536u + (uint32_t)x) * 64u + (uint32_t)s;
                float sx = 0.5f, sy = 0.5f;
                if (opt->spp > 1) {
                    sx = ((float)(s % strata) + hash01(seed, 1, 0)) / (float)strata;
                    sy = ((float)(s / strata % strata) + hash01(seed, 2, 0)) / (float)strata;
                }
                float px = (2.0f * ((float)x + sx) / (float)job->width - 1.0f) * tan_half * aspect;
                float py = (1.0f - 2.0f * ((float)y + sy) / (float)job->height) * tan_half;
                vec3 d = add(job->cam_fwd, add(scale(job->cam_right, px), scale(job->cam_up, py)));
                count->camera++;
                sum = add(sum, shade(job, job->cam_eye, d, 0.0f, 0, seed, count));
            }
            float *out = job->rgb + ((size_t)y * (size_t)job->width + (size_t)x) * 3;
            out[0] = sum.x / (float)opt->spp;
            out[1] = sum.y / (float)opt->spp;
            out[2] = sum.z / (float)opt->spp;
        }
    }
}

typedef struct {
    render_job *job;
    ray_counts count;
} worker_arg;

static void *worker(void *p)
{
    worker_arg *w = p;
    render_job *job = w->job;
    int tiles = job->tiles_x * job->tiles_y;
    for (;;) {
        int t = atomic_fetch_add(&job->next_tile, 1);
        if (t >= tiles) break;
        render_tile(job, t, &w->count);
        int done = atomic_fetch_add(&job->tiles_done, 1) + 1;
        if (job->opt->progress) {
            pthread_mutex_lock(&job->progress_lock);
            job->opt->progress(job->opt->progress_ctx, (double)done / (double)tiles);
            pthread_mutex_unlock(&job->progress_lock);
        }
    }
    return NULL;
}

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

bool lanes_render(const lanes_scene *scene, const lanes_accel *accel,
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
        snprintf(err->message, sizeof err->message, "render: instruction set '%s' is not available",
                 lanes_isa_name(opt->isa));
        return false;
    }
    if (opt->scheme == LANES_SCHEME_WIDE && accel->wide.width != job.k->wide_width) {
        snprintf(err->message, sizeof err->message,
                 "render: the wide scheme at %s needs a %d-wide BVH (have %d)", job.k->name,
                 job.k->wide_width, accel->wide.width);
        return false;
    }
    job.width = opt->width > 0 ? opt->width : scene->camera.width;
    job.height = opt->height > 0 ? opt->height : scene->camera.height;
    if (job.width <= 0 || job.height <= 0 || job.width > 16384 || job.height > 16384 ||
        opt->spp < 1 || opt->spp > 65536) {
        snprintf(err->message, sizeof err->message,
                 "render: image size %dx%d or %d samples per pixel out of range (1..16384, 1..65536)",
                 job.width, job.height, opt->spp);
        return false;
    }
    float lo[3], hi[3];
    lanes_scene_bounds(scene, lo, hi);
    vec3 diag = sub(v3_load(hi), v3_load(lo));
    job.eps = 1e-5f * sqrtf(dot(diag, diag)) + 1e-6f;

    const lanes_camera *c = &scene->camera;
    job.cam_eye = v3_load(c->eye);
    job.cam_fwd = normalize(sub(v3_load(c->target), job.cam_eye));
    job.cam_right = normalize(cross(job.cam_fwd, v3_load(c->up)));
    job.cam_up = cross(job.cam_right, job.cam_fwd);

    job.rgb = calloc((size_t)job.width * (size_t)job.height * 3, sizeof(float));
    if (!job.rgb) {
        snprintf(err->message, sizeof err->message, "render: out of memory for the image");
        return false;
    }
    job.tiles_x = (job.width + 15) / 16;
    job.tiles_y = (job.height + 15) / 16;
    pthread_mutex_init(&job.progress_lock, NULL);

    int threads = opt->threads > 0 ? opt->threads : (int)sysconf(_SC_NPROCESSORS_ONLN);
    if (threads < 1) threads = 1;
    if (threads > 256) threads = 256;
    worker_arg args[256];
    pthread_t tid[256];
    double t0 = now_seconds();
    int started = 0;
    for (int i = 0; i < threads; i++) {
        args[i] = (worker_arg){&job, {0, 0, 0}};
        if (i > 0 && pthread_create(&tid[i], NULL, worker, &args[i]) != 0) break;
        started = i + 1;
    }
    worker(&args[0]); /* the calling thread works too */
    for (int i = 1; i < started; i++) pthread_join(tid[i], NULL);
    out->seconds = now_seconds() - t0;
    pthread_mutex_destroy(&job.progress_lock);

    for (int i = 0; i < started; i++) {
        out->camera_rays += args[i].count.camera;
        out->shadow_rays += args[i].count.shadow;
        out->secondary_rays += args[i].count.secondary;
    }
    out->rays = out->camera_rays + out->shadow_rays + out->secondary_rays;
    out->rgb = job.rgb;
    out->width = job.width;
    out->height = job.height;
    return true;
}

void lanes_render_result_free(lanes_render_result *r)
{
    free(r->rgb);
    memset(r, 0, sizeof *r);
}
