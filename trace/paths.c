/* The path tracer's single-path methods (see paths.h): threads take 16x16
 * tiles from a shared counter, and trace each pixel's samples one path at
 * a time. */
#include "trace/paths.h"

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "build/camera.h"
#include "build/parallel.h"
#include "simd/counter_random.h"
#include "trace/material_sort.h"
#include "trace/scene_plan.h"
#include "trace/shading.h"

static const char *const method_names[LANES_PATHS_METHOD_COUNT] = {"single", "single-1lane", "packet", "stream"};

const char *lanes_paths_method_name(lanes_paths_method m)
{
    return (unsigned)m < LANES_PATHS_METHOD_COUNT ? method_names[m] : "?";
}

int lanes_paths_method_from_name(const char *name)
{
    for (int i = 0; i < LANES_PATHS_METHOD_COUNT; i++)
        if (strcmp(name, method_names[i]) == 0) return i;
    return -1;
}

void lanes_paths_default_options(lanes_paths_options *o)
{
    memset(o, 0, sizeof *o);
    o->isa = lanes_isa_current();
    o->method = LANES_PATHS_SINGLE;
    o->accuracy = LANES_ACCURACY_FROM_SCENE;
    o->spp = 16;
    o->depth = 8;
    o->stream = 2048;
}

/* The dimensions a path vertex draws. */
enum { DIM_PIXEL_X, DIM_PIXEL_Y, DIM_LIGHT, DIM_LIGHT_U, DIM_LIGHT_V, DIM_BSDF_1, DIM_BSDF_2, DIM_BSDF_3, DIM_ROULETTE };


/* ---- the scene as the integrator reads it ------------------------------ */

typedef struct {
    bool area;       /* else a point light */
    uint32_t index;  /* into the scene's point or area lights */
    float area_size; /* parallelogram area */
    vec3 normal;     /* parallelogram's emitting side */
} light_ref;

typedef struct {
    const lanes_scene *scene;
    const lanes_render_accel *accel;
    const lanes_paths_options *opt;
    lanes_accuracy accuracy;
    lanes_rcp_mode rcp;
    float eps;
    const lanes_kernels *trace_k, *shade_k;
    lanes_view view;
    lanes_bsdf *bsdf;       /* per material */
    lanes_texture *texture; /* per material: its albedo, where textured */
    bool *textured;
    bool *area_light_quad;  /* per material: shows a parallelogram light */
    light_ref *lights;
    float *light_cdf;       /* light_count + 1 entries, light_cdf[light_count] = 1 */
    size_t light_count;
    float *rgb, *rgb2;
    int width, height, tiles_x, tiles_y;
} paths_job;

typedef struct stream_state stream_state;

typedef struct {
    uint64_t paths, finished, accounting_errors, shadow, by_depth[LANES_PATHS_MAX_DEPTH + 1];
    uint64_t shade_calls, shade_slots, shade_live;
    uint64_t sample_calls, sample_slots, sample_live; /* the bsdf_sample calls among them */
    double stage_seconds[LANES_PATHS_STAGE_COUNT];
    stream_state *stream; /* the worker's streams (stream method) */
} paths_counts;

/* A shading kernel call of the set's width that carried live items. */
static void count_shading(paths_counts *c, int width, int live, bool sampling)
{
    c->shade_calls++, c->shade_slots += (uint64_t)width, c->shade_live += (uint64_t)live;
    if (sampling) c->sample_calls++, c->sample_slots += (uint64_t)width, c->sample_live += (uint64_t)live;
}

static float luminance(const float c[3]) { return (c[0] + c[1] + c[2]) / 3.0f; }

static lanes_bsdf bsdf_of(const lanes_material *m)
{
    lanes_bsdf b;
    memset(&b, 0, sizeof b);
    switch (m->kind) {
    case LANES_MAT_MIRROR: b.kind = LANES_BSDF_MIRROR; break;
    case LANES_MAT_GLASS: b.kind = m->roughness > 0.0f ? LANES_BSDF_ROUGH_GLASS : LANES_BSDF_GLASS; break;
    case LANES_MAT_CONDUCTOR: b.kind = LANES_BSDF_CONDUCTOR; break;
    case LANES_MAT_PLASTIC: b.kind = LANES_BSDF_PLASTIC; break;
    default: b.kind = LANES_BSDF_LAMBERT; break; /* an emitter is never shaded */
    }
    memcpy(b.albedo, m->color, sizeof b.albedo);
    memcpy(b.f0, m->f0, sizeof b.f0);
    b.roughness = m->roughness;
    b.ior = m->ior;
    return b;
}

static lanes_texture texture_of(const lanes_material *m)
{
    /* the material's texture, not NONE: the four in the same order */
    static const lanes_texture_kind kinds[] = {LANES_TEXTURE_CHECKER, LANES_TEXTURE_NOISE, LANES_TEXTURE_MARBLE,
                                               LANES_TEXTURE_WOOD};
    lanes_texture t;
    memset(&t, 0, sizeof t);
    t.kind = kinds[m->texture - LANES_MAT_TEXTURE_CHECKER];
    t.scale = m->texture_scale;
    memcpy(t.color_a, m->texture_colors[0], sizeof t.color_a);
    memcpy(t.color_b, m->texture_colors[1], sizeof t.color_b);
    return t;
}

/* The albedo at n surface points p (SoA) of material mat, into albedo
 * (SoA): the bsdf kernels' albedo argument, NULL for an untextured
 * material (its own color). */
static const float *albedo_at(const paths_job *job, uint32_t mat, size_t n, const float *p, float *albedo)
{
    if (!job->textured[mat]) return NULL;
    float weight[LANES_MAX_W];
    job->shade_k->texture_color(&job->texture[mat], n, p, weight, albedo);
    return albedo;
}

/* Lights with their selection probabilities, by power: a point light's
 * 4 pi I, a parallelogram's pi A Le (one-sided), by the channels' mean. */
static bool prepare_lights(paths_job *job)
{
    const lanes_scene *s = job->scene;
    size_t n = s->point_light_count + s->area_light_count;
    job->lights = calloc(n + 1, sizeof *job->lights);
    job->light_cdf = calloc(n + 1, sizeof *job->light_cdf);
    if (!job->lights || !job->light_cdf) return false;
    double *power = calloc(n + 1, sizeof *power), total = 0.0;
    if (!power) return false;
    size_t k = 0;
    for (size_t i = 0; i < s->point_light_count; i++) {
        double p = 4.0 * LANES_PI * luminance(s->point_lights[i].intensity);
        if (!(p > 0.0)) continue;
        job->lights[k] = (light_ref){false, (uint32_t)i, 0.0f, v3(0, 0, 0)};
        power[k++] = p, total += p;
    }
    for (size_t i = 0; i < s->area_light_count; i++) {
        const lanes_area_light *al = &s->area_lights[i];
        float area;
        vec3 ln = v3_unit_normal_area(v3_load(al->edge_u), v3_load(al->edge_v), &area);
        double p = LANES_PI * area * luminance(al->emission);
        if (!(p > 0.0)) continue;
        job->lights[k] = (light_ref){true, (uint32_t)i, area, ln};
        power[k++] = p, total += p;
    }
    job->light_count = total > 0.0 ? k : 0;
    double run = 0.0;
    for (size_t i = 0; i < job->light_count; i++) {
        job->light_cdf[i] = (float)(run / total);
        run += power[i];
    }
    job->light_cdf[job->light_count] = 1.0f;
    free(power);
    return true;
}

/* ---- tracing one ray --------------------------------------------------- */

/* n rays through the set's traversal or the caller's intersector. */
static void trace_rays(const paths_job *job, const lanes_ray *rays, size_t n, lanes_hit *hits)
{
    const lanes_paths_intersector *x = job->opt->intersector;
    if (x) x->trace(x->ctx, rays, n, hits);
    else job->trace_k->trace_wide(&job->accel->wide, job->accuracy, rays, n, hits, NULL);
}

static void occluded_rays(const paths_job *job, const lanes_ray *rays, size_t n, uint8_t *occluded)
{
    const lanes_paths_intersector *x = job->opt->intersector;
    if (x) x->occluded(x->ctx, rays, n, occluded);
    else job->trace_k->occluded_wide(&job->accel->wide, job->accuracy, rays, n, occluded, NULL);
}

/* A path's next ray, from o along d without end, prepared for tracing. */
static lanes_ray extension_ray(const paths_job *job, vec3 o, vec3 d)
{
    lanes_ray r = {{o.x, o.y, o.z}, {d.x, d.y, d.z}, {0, 0, 0}, 0.0f, INFINITY};
    lanes_ray_prepare_rcp(&r, job->rcp);
    return r;
}

static lanes_hit trace(const paths_job *job, vec3 o, vec3 d)
{
    lanes_ray r = extension_ray(job, o, d);
    lanes_hit h;
    trace_rays(job, &r, 1, &h);
    return h;
}

static bool occluded(const paths_job *job, const lanes_ray *r)
{
    uint8_t hit = 0;
    occluded_rays(job, r, 1, &hit);
    return hit != 0;
}

/* ---- the shading frame --------------------------------------------------- */

/* An orthonormal frame around the unit normal n (Duff et al. 2017). */
typedef struct {
    vec3 t, b, n;
} frame;

static frame frame_around(vec3 n)
{
    float sign = copysignf(1.0f, n.z), a = -1.0f / (sign + n.z), b = n.x * n.y * a;
    return (frame){v3(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x), v3(b, sign + n.y * n.y * a, -n.y), n};
}

/* The shading frame of a surface: around the triangle's own normal (by its
 * winding), whichever side the ray came from. Made where it is needed, not
 * kept with a path in flight. */
static frame surface_frame(const lanes_surface *sf) { return frame_around(sf->front ? sf->nf : v3_scale(sf->nf, -1.0f)); }

static vec3 to_local(const frame *f, vec3 v) { return v3(v3_dot(v, f->t), v3_dot(v, f->b), v3_dot(v, f->n)); }

static vec3 to_world(const frame *f, vec3 v)
{
    return v3_add(v3_scale(f->t, v.x), v3_add(v3_scale(f->b, v.y), v3_scale(f->n, v.z)));
}

/* f(wo, wi) through the shading kernels (one item). */
static vec3 bsdf_f(const paths_job *job, const lanes_bsdf *b, const float *albedo, vec3 wo, vec3 wi, paths_counts *c)
{
    float o[3] = {wo.x, wo.y, wo.z}, i[3] = {wi.x, wi.y, wi.z}, f[3], pdf;
    job->shade_k->bsdf_eval(b, 1, albedo, o, i, f, &pdf);
    count_shading(c, job->shade_k->lanes, 1, false);
    return v3(f[0], f[1], f[2]);
}

/* A hit's triangle and material, asked of memory ahead of path_vertex:
 * methods that hold many hits at once overlap the cache misses that one
 * path at a time waits out one by one. */
enum { PREFETCH_AHEAD = 8 };

static void prefetch_hit(const lanes_scene *s, const lanes_hit *h)
{
    if (h->prim == LANES_NO_HIT) return;
    const float *v = s->verts + (size_t)h->prim * 9;
    __builtin_prefetch(v);
    __builtin_prefetch(v + 8); /* 36 bytes may straddle two lines */
    __builtin_prefetch(&s->material_of[h->prim]);
}

/* ---- one path ------------------------------------------------------------ */

static vec3 background(const paths_job *job, vec3 d)
{
    if (job->opt->uniform_background) return v3_load(job->opt->background);
    return lanes_background(d);
}

/* A shadow ray's set-up: one light chosen by power, a point on it, the
 * direction in the shading frame (wi, for the BSDF) and what arrives along
 * it, over the probability of the choice (scale); `active` false when the
 * light cannot reach the surface. */
typedef struct {
    bool active;
    vec3 target, wi, wi_local, radiance;
    float scale;
} light_sample;

static light_sample light_pick(const paths_job *job, const lanes_surface *sf, const frame *fr, uint32_t pixel,
                               uint32_t sample, uint32_t depth)
{
    light_sample ls;
    memset(&ls, 0, sizeof ls);
    if (job->light_count == 0) return ls;
    const lanes_scene *s = job->scene;
    float u = lanes_random01(pixel, sample, depth, DIM_LIGHT);
    size_t k = 0;
    while (k + 1 < job->light_count && job->light_cdf[k + 1] <= u) k++;
    float pick = job->light_cdf[k + 1] - job->light_cdf[k];
    const light_ref *l = &job->lights[k];
    float geometry; /* the light's area times its cosine, or 1 for a point */
    if (l->area) {
        const lanes_area_light *al = &s->area_lights[l->index];
        float a = lanes_random01(pixel, sample, depth, DIM_LIGHT_U), bb = lanes_random01(pixel, sample, depth, DIM_LIGHT_V);
        ls.target = v3_add(v3_load(al->corner), v3_add(v3_scale(v3_load(al->edge_u), a), v3_scale(v3_load(al->edge_v), bb)));
        ls.radiance = v3_load(al->emission);
        geometry = l->area_size;
    } else {
        ls.target = v3_load(s->point_lights[l->index].position);
        ls.radiance = v3_load(s->point_lights[l->index].intensity);
        geometry = 1.0f;
    }
    vec3 to = v3_sub(ls.target, sf->p);
    float dist2 = v3_dot(to, to), dist = sqrtf(dist2);
    if (!(dist > 0.0f)) return ls;
    ls.wi = v3_scale(to, 1.0f / dist);
    if (l->area) {
        float cos_l = -v3_dot(l->normal, ls.wi);
        if (cos_l <= 0.0f) return ls;
        geometry *= cos_l;
    }
    ls.wi_local = to_local(fr, ls.wi);
    ls.scale = fabsf(ls.wi_local.z) * geometry / (dist2 * pick);
    ls.active = true;
    return ls;
}

/* The shadow ray toward a light sample, prepared for tracing; false when
 * it has no length. It leaves from off the surface, on the light's side,
 * and must stop short of the light by its own length from there: a
 * visible parallelogram is geometry too, and measured from sf->p the ray
 * ran past the target (by the offset over the sine of its angle) into the
 * light's own triangles. */
static bool shadow_ray(const paths_job *job, const lanes_surface *sf, const light_sample *ls, lanes_ray *r)
{
    vec3 side = v3_dot(ls->wi, sf->nf) > 0.0f ? sf->nf : v3_scale(sf->nf, -1.0f);
    vec3 origin = lanes_offset_origin(sf, side, job->accuracy, job->eps);
    vec3 path = v3_sub(ls->target, origin);
    float length = sqrtf(v3_dot(path, path));
    if (!(length > 0.0f)) return false;
    vec3 dir = v3_scale(path, 1.0f / length);
    *r = (lanes_ray){{origin.x, origin.y, origin.z}, {dir.x, dir.y, dir.z}, {0, 0, 0}, 0.0f, length * (1.0f - 1e-4f)};
    lanes_ray_prepare_rcp(r, job->rcp);
    return true;
}

/* What an unblocked light sample brings through the BSDF value f. */
static vec3 light_value(const light_sample *ls, vec3 f) { return v3_scale(v3_mul(f, ls->radiance), ls->scale); }

static bool is_black(vec3 f) { return f.x == 0.0f && f.y == 0.0f && f.z == 0.0f; }

/* The light the sample brings through the BSDF value f, its shadow ray
 * traced at once. */
static vec3 light_finish(const paths_job *job, const lanes_surface *sf, const light_sample *ls, vec3 f,
                         paths_counts *c)
{
    if (is_black(f)) return v3(0, 0, 0);
    c->shadow++;
    lanes_ray r;
    if (!shadow_ray(job, sf, ls, &r) || occluded(job, &r)) return v3(0, 0, 0);
    return light_value(ls, f);
}

/* Light arriving at the surface from one light chosen by power, through
 * the BSDF towards wo, over the probability of the choice; 0 when the
 * shadow ray is blocked. */
static vec3 next_event(const paths_job *job, const lanes_surface *sf, const frame *fr, const lanes_bsdf *b,
                       const float *albedo, vec3 wo_local, uint32_t pixel, uint32_t sample, uint32_t depth,
                       paths_counts *c)
{
    light_sample ls = light_pick(job, sf, fr, pixel, sample, depth);
    if (!ls.active) return v3(0, 0, 0);
    return light_finish(job, sf, &ls, bsdf_f(job, b, albedo, wo_local, ls.wi_local, c), c);
}

/* Where a path's ray arrives, for every method alike: a miss adds the
 * background, a hit its emission where it counts; false when the path
 * ends there (a miss or an emitter), else the surface, its material and
 * wo in its shading frame (surface_frame: the triangle's own normal, by
 * its winding; glass tells inside from outside by it, the opaque BSDFs
 * are two-sided). */
static bool path_vertex(const paths_job *job, const lanes_hit *h, vec3 d, vec3 beta, bool after_delta, vec3 *sum,
                        lanes_surface *sf, uint32_t *material, vec3 *wo)
{
    if (h->prim == LANES_NO_HIT) {
        *sum = v3_add(*sum, v3_mul(beta, background(job, d)));
        return false;
    }
    const lanes_scene *s = job->scene;
    *sf = lanes_surface_at(s, h, d);
    *material = s->material_of[h->prim];
    const lanes_material *m = &s->materials[*material];
    if (m->kind == LANES_MAT_EMISSIVE || m->kind == LANES_MAT_DIFFUSE) {
        bool counts = job->area_light_quad[*material] ? after_delta && sf->front : true;
        if (counts) *sum = v3_add(*sum, v3_mul(beta, v3_load(m->emission)));
    }
    if (m->kind == LANES_MAT_EMISSIVE) return false;
    frame fr = surface_frame(sf);
    *wo = to_local(&fr, v3_scale(v3_normalize(d), -1.0f));
    return true;
}

/* The camera ray's direction for a pixel's sample: sample 0 through the
 * pixel's centre, the others jittered. */
static vec3 camera_dir(const paths_job *job, uint32_t pixel, uint32_t sample)
{
    uint32_t x = pixel % (uint32_t)job->width, y = pixel / (uint32_t)job->width;
    float sx = 0.5f, sy = 0.5f;
    if (sample > 0)
        sx = lanes_random01(pixel, sample, 0, DIM_PIXEL_X), sy = lanes_random01(pixel, sample, 0, DIM_PIXEL_Y);
    return lanes_view_dir(&job->view, (float)x + sx, (float)y + sy);
}

/* Where an extension ray with the BSDF's weight w3 leaves along wi (shading
 * frame): the new throughput, or false when the roulette ends the path. */
static bool continue_path(const paths_job *job, const lanes_surface *sf, const frame *fr, const float wi3[3],
                          const float w3[3], int depth, uint32_t pixel, uint32_t sample, vec3 *beta, vec3 *o, vec3 *d)
{
    *beta = v3_mul(*beta, v3(w3[0], w3[1], w3[2]));
    if (depth + 1 >= 3) {
        float survive = fminf(1.0f, fmaxf(beta->x, fmaxf(beta->y, beta->z)));
        if (!(lanes_random01(pixel, sample, (uint32_t)depth, DIM_ROULETTE) < survive)) return false;
        *beta = v3_scale(*beta, 1.0f / survive);
    }
    vec3 wi = to_world(fr, v3(wi3[0], wi3[1], wi3[2]));
    vec3 side = v3_dot(wi, sf->nf) > 0.0f ? sf->nf : v3_scale(sf->nf, -1.0f);
    *o = lanes_offset_origin(sf, side, job->accuracy, job->eps);
    *d = wi;
    return true;
}

static vec3 trace_path(const paths_job *job, vec3 eye, vec3 dir, uint32_t pixel, uint32_t sample,
                       paths_counts *c)
{
    vec3 sum = v3(0, 0, 0), beta = v3(1, 1, 1), o = eye, d = dir;
    bool after_delta = true; /* the camera ray counts as one */
    c->paths++;
    for (int depth = 0; depth < job->opt->depth; depth++) {
        c->by_depth[depth]++;
        lanes_hit h = trace(job, o, d);
        lanes_surface sf;
        uint32_t mi;
        vec3 wo;
        if (!path_vertex(job, &h, d, beta, after_delta, &sum, &sf, &mi, &wo)) break;
        frame fr = surface_frame(&sf);
        const lanes_bsdf *b = &job->bsdf[mi];
        float p3[3] = {sf.p.x, sf.p.y, sf.p.z}, albedo3[3];
        const float *albedo = albedo_at(job, mi, 1, p3, albedo3);
        bool delta = b->kind == LANES_BSDF_MIRROR || b->kind == LANES_BSDF_GLASS;
        if (!delta)
            sum = v3_add(sum, v3_mul(beta, next_event(job, &sf, &fr, b, albedo, wo, pixel, sample, (uint32_t)depth, c)));

        float wo3[3] = {wo.x, wo.y, wo.z}, u3[3], wi3[3], w3[3], pdf;
        uint8_t flags;
        u3[0] = lanes_random01(pixel, sample, (uint32_t)depth, DIM_BSDF_1);
        u3[1] = lanes_random01(pixel, sample, (uint32_t)depth, DIM_BSDF_2);
        u3[2] = lanes_random01(pixel, sample, (uint32_t)depth, DIM_BSDF_3);
        job->shade_k->bsdf_sample(b, 1, albedo, wo3, u3, wi3, w3, &pdf, &flags);
        count_shading(c, job->shade_k->lanes, 1, true);
        if (!(flags & LANES_BSDF_VALID)) break;
        after_delta = (flags & LANES_BSDF_DELTA) != 0;
        if (!continue_path(job, &sf, &fr, wi3, w3, depth, pixel, sample, &beta, &o, &d)) break;
    }
    return sum;
}

/* Adds the time since `since` to *acc; returns now. */
static double stage_clock(double *acc, double since)
{
    double now = lanes_render_clock();
    *acc += now - since;
    return now;
}

/* ---- a tile's sums -------------------------------------------------------- */

/* A tile's pixels' samples summed, and their squares (for the per-sample
 * variance), in sample order. */
typedef struct {
    vec3 sum[256], sq[256];
} tile_sums;

static void add_sample(tile_sums *t, int k, vec3 v)
{
    t->sum[k] = v3_add(t->sum[k], v);
    t->sq[k] = v3_add(t->sq[k], v3_mul(v, v));
}

/* ---- packets: W paths at once ------------------------------------------- */

/* A path of a packet, between bounces. */
typedef struct {
    vec3 o, d, beta, sum, wo;
    uint32_t pixel, sample, material;
    bool alive, after_delta;
    lanes_surface sf;
    /* the path's bounce and its pixel in the tile (streams), and its
     * sampled direction until the shadow rays are traced */
    uint32_t ss_depth, tile_index;
    uint8_t pending_flags;
    float pending_wi[3], pending_w[3];
} packet_lane;

/* Directions in SoA form for one shading call over the packet's W lanes;
 * lanes outside the call hold a harmless direction. */
typedef struct {
    float wo[3 * LANES_MAX_W], wi[3 * LANES_MAX_W], u[3 * LANES_MAX_W], f[3 * LANES_MAX_W], w[3 * LANES_MAX_W];
    float p[3 * LANES_MAX_W], albedo[3 * LANES_MAX_W];
    float pdf[LANES_MAX_W];
    uint8_t flags[LANES_MAX_W];
} packet_soa;

static void soa_put(float *soa, int w, int i, vec3 v) { soa[i] = v.x, soa[w + i] = v.y, soa[2 * w + i] = v.z; }

/* Embree's ISPC path tracer in shape: the packet's paths go on together;
 * at each bounce every material present shades under its lane mask, one
 * call of W lanes each (the others idle: the utilisation counted), and a
 * path that ends leaves its lane empty. Each lane computes what
 * single-1lane computes for its path, operation for operation. */
static void trace_packet_paths(const paths_job *job, const uint32_t *pixel, const uint32_t *sample, int n, vec3 *sum,
                               paths_counts *c)
{
    const int w = job->shade_k->lanes;
    packet_lane L[LANES_MAX_W];
    packet_soa q;
    lanes_ray shadow[LANES_MAX_W];
    vec3 shadow_add[LANES_MAX_W];
    int shadow_lane[LANES_MAX_W];
    uint8_t blocked[LANES_MAX_W];
    light_sample ls[LANES_MAX_W]; /* each lane's light sample, while its material shades */
    double *stage = c->stage_seconds, t = lanes_render_clock();
    for (int i = 0; i < n; i++) {
        memset(&L[i], 0, sizeof L[i]);
        L[i].pixel = pixel[i], L[i].sample = sample[i];
        L[i].alive = L[i].after_delta = true;
        L[i].beta = v3(1, 1, 1);
        L[i].o = job->view.eye;
        L[i].d = camera_dir(job, pixel[i], sample[i]);
        c->paths++;
    }
    t = stage_clock(&stage[LANES_PATHS_STAGE_GENERATE], t);
    for (int depth = 0; depth < job->opt->depth; depth++) {
        bool any = false;
        /* the live lanes' rays in one call, compact */
        lanes_ray rays[LANES_MAX_W];
        lanes_hit found[LANES_MAX_W], hits[LANES_MAX_W];
        int nr = 0;
        for (int i = 0; i < n; i++)
            if (L[i].alive) rays[nr++] = extension_ray(job, L[i].o, L[i].d);
        trace_rays(job, rays, (size_t)nr, found);
        for (int k = 0; k < nr; k++) prefetch_hit(job->scene, &found[k]);
        for (int i = 0, k = 0; i < n; i++)
            if (L[i].alive) hits[i] = found[k++];
        t = stage_clock(&stage[LANES_PATHS_STAGE_INTERSECT], t);
        for (int i = 0; i < n; i++) {
            packet_lane *l = &L[i];
            if (!l->alive) continue;
            c->by_depth[depth]++;
            l->alive = path_vertex(job, &hits[i], l->d, l->beta, l->after_delta, &l->sum, &l->sf, &l->material, &l->wo);
            any = any || l->alive;
        }
        if (!any) {
            stage_clock(&stage[LANES_PATHS_STAGE_SHADE], t);
            break;
        }
        int nsh = 0;
        /* each material present, in the order its first lane comes */
        uint32_t pending = 0;
        for (int i = 0; i < n; i++) pending |= (uint32_t)L[i].alive << i;
        while (pending) {
            uint32_t mat = L[__builtin_ctz(pending)].material, mask = 0;
            for (int i = 0; i < n; i++)
                if ((pending >> i & 1u) && L[i].material == mat) mask |= 1u << i;
            pending &= ~mask;
            const lanes_bsdf *b = &job->bsdf[mat];
            const vec3 up = v3(0, 0, 1);
            for (int i = 0; job->textured[mat] && i < w; i++) soa_put(q.p, w, i, i < n && (mask >> i & 1u) ? L[i].sf.p : up);
            const float *albedo = albedo_at(job, mat, (size_t)w, q.p, q.albedo);
            if (b->kind != LANES_BSDF_MIRROR && b->kind != LANES_BSDF_GLASS) {
                uint32_t lit = 0;
                for (int i = 0; i < w; i++) {
                    bool in = i < n && (mask >> i & 1u);
                    if (in) {
                        frame fr = surface_frame(&L[i].sf);
                        ls[i] = light_pick(job, &L[i].sf, &fr, L[i].pixel, L[i].sample, (uint32_t)depth);
                    }
                    bool active = in && ls[i].active;
                    lit |= (uint32_t)active << i;
                    soa_put(q.wo, w, i, active ? L[i].wo : up);
                    soa_put(q.wi, w, i, active ? ls[i].wi_local : up);
                }
                if (lit) {
                    job->shade_k->bsdf_eval(b, (size_t)w, albedo, q.wo, q.wi, q.f, q.pdf);
                    count_shading(c, w, __builtin_popcount(lit), false);
                    for (int i = 0; i < n; i++) {
                        vec3 f = v3(q.f[i], q.f[w + i], q.f[2 * w + i]);
                        if (!(lit >> i & 1u) || is_black(f)) continue;
                        c->shadow++;
                        if (!shadow_ray(job, &L[i].sf, &ls[i], &shadow[nsh])) continue;
                        shadow_lane[nsh] = i;
                        shadow_add[nsh++] = v3_mul(L[i].beta, light_value(&ls[i], f));
                    }
                }
            }
            for (int i = 0; i < w; i++) {
                bool in = i < n && (mask >> i & 1u);
                soa_put(q.wo, w, i, in ? L[i].wo : up);
                for (int k = 0; k < 3; k++)
                    q.u[k * w + i] = in ? lanes_random01(L[i].pixel, L[i].sample, (uint32_t)depth, DIM_BSDF_1 + (uint32_t)k) : 0.5f;
            }
            job->shade_k->bsdf_sample(b, (size_t)w, albedo, q.wo, q.u, q.wi, q.w, q.pdf, q.flags);
            count_shading(c, w, __builtin_popcount(mask), true);
            for (int i = 0; i < n; i++) {
                if (!(mask >> i & 1u)) continue;
                packet_lane *l = &L[i];
                if (!(q.flags[i] & LANES_BSDF_VALID)) {
                    l->alive = false;
                    continue;
                }
                l->pending_flags = q.flags[i];
                for (int k = 0; k < 3; k++) l->pending_wi[k] = q.wi[k * w + i], l->pending_w[k] = q.w[k * w + i];
            }
        }
        t = stage_clock(&stage[LANES_PATHS_STAGE_SHADE], t);
        /* the packet's shadow rays in one call; each path's light before
         * its next bounce, as single-1lane adds them */
        occluded_rays(job, shadow, (size_t)nsh, blocked);
        for (int k = 0; k < nsh; k++)
            if (!blocked[k]) L[shadow_lane[k]].sum = v3_add(L[shadow_lane[k]].sum, shadow_add[k]);
        t = stage_clock(&stage[LANES_PATHS_STAGE_SHADOW], t);
        for (int i = 0; i < n; i++) {
            packet_lane *l = &L[i];
            if (!l->alive) continue;
            l->after_delta = (l->pending_flags & LANES_BSDF_DELTA) != 0;
            frame fr = surface_frame(&l->sf);
            l->alive = continue_path(job, &l->sf, &fr, l->pending_wi, l->pending_w, depth, l->pixel, l->sample, &l->beta,
                                     &l->o, &l->d);
        }
        t = stage_clock(&stage[LANES_PATHS_STAGE_ACCUMULATE], t);
    }
    for (int i = 0; i < n; i++) sum[i] = L[i].sum;
}

/* A tile's paths in packets of W: sample by sample, W pixels of the tile
 * in scanline order at a time (coherent camera rays). */
static void render_tile_packets(const paths_job *job, const uint32_t *tile_pixel, int count, tile_sums *acc, paths_counts *c)
{
    const int w = job->shade_k->lanes;
    for (int s = 0; s < job->opt->spp; s++)
        for (int first = 0; first < count; first += w) {
            int n = count - first < w ? count - first : w;
            uint32_t samples[LANES_MAX_W];
            vec3 sums[LANES_MAX_W];
            for (int i = 0; i < n; i++) samples[i] = (uint32_t)s;
            trace_packet_paths(job, tile_pixel + first, samples, n, sums, c);
            for (int i = 0; i < n; i++) add_sample(acc, first + i, sums[i]);
            c->finished += (uint64_t)n;
        }
}

/* ---- streams: sorted by material ------------------------------------------ */

/* A worker's streams (Afra et al. 2016): S paths in flight, their
 * extension rays and their shadow rays, compact; the paths that need
 * shading sorted by material, shaded in batches of W in that order. */
struct stream_state {
    int size;
    packet_lane *path;    /* slot -> path */
    lanes_ray *rays;      /* extension rays of the live slots, compact */
    lanes_hit *hits;
    uint32_t *ray_slot;   /* ray i is slot ray_slot[i]'s */
    uint32_t *shade_slot; /* the slots to shade, compact, and their materials */
    uint32_t *shade_material;
    uint32_t *offsets, *sorted; /* the material sort */
    lanes_ray *shadow;    /* shadow rays, compact, and the slot each serves */
    uint32_t *shadow_slot;
    vec3 *shadow_add;
    uint8_t *occluded;
    uint32_t *free_slots;
    vec3 *radiance;       /* per (pixel of the tile, sample of the chunk) */
};

/* Samples of a tile in flight at once: their radiance is kept per
 * (pixel, sample) and summed in sample order when the chunk is done, so
 * the image is the same bit for bit as the other methods'. */
enum { STREAM_CHUNK_SAMPLES = 64 };

/* A chunk's samples for spp samples per pixel. */
static int chunk_samples(int spp) { return spp < STREAM_CHUNK_SAMPLES ? spp : STREAM_CHUNK_SAMPLES; }

static size_t stream_bytes(int size, size_t materials, int spp)
{
    return (size_t)size * (sizeof(packet_lane) + 2 * sizeof(lanes_ray) + sizeof(lanes_hit) + 6 * sizeof(uint32_t) +
                           sizeof(vec3) + 1) +
           (materials + 1) * sizeof(uint32_t) + 256 * (size_t)chunk_samples(spp) * sizeof(vec3);
}

static void stream_free(stream_state *st)
{
    if (!st) return;
    free(st->path), free(st->rays), free(st->hits), free(st->ray_slot), free(st->shade_slot);
    free(st->shade_material), free(st->offsets), free(st->sorted), free(st->shadow), free(st->shadow_slot);
    free(st->shadow_add), free(st->occluded), free(st->free_slots), free(st->radiance);
    memset(st, 0, sizeof *st);
}

static bool stream_alloc(stream_state *st, int size, size_t materials, int spp)
{
    size_t n = (size_t)size;
    st->size = size;
    st->path = calloc(n, sizeof *st->path);
    st->rays = calloc(n, sizeof *st->rays);
    st->hits = calloc(n, sizeof *st->hits);
    st->ray_slot = calloc(n, sizeof *st->ray_slot);
    st->shade_slot = calloc(n, sizeof *st->shade_slot);
    st->shade_material = calloc(n, sizeof *st->shade_material);
    st->offsets = calloc(materials + 1, sizeof *st->offsets);
    st->sorted = calloc(n, sizeof *st->sorted);
    st->shadow = calloc(n, sizeof *st->shadow);
    st->shadow_slot = calloc(n, sizeof *st->shadow_slot);
    st->shadow_add = calloc(n, sizeof *st->shadow_add);
    st->occluded = calloc(n, 1);
    st->free_slots = calloc(n, sizeof *st->free_slots);
    st->radiance = calloc(256 * (size_t)chunk_samples(spp), sizeof *st->radiance);
    return st->path && st->rays && st->hits && st->ray_slot && st->shade_slot && st->shade_material && st->offsets &&
           st->sorted && st->shadow && st->shadow_slot && st->shadow_add && st->occluded && st->free_slots &&
           st->radiance;
}


/* The paths (tile pixel p, sample s) for s in [s0, s1), streamed. */
static void stream_chunk(const paths_job *job, stream_state *st, const uint32_t *tile_pixel, int count, int s0, int s1,
                         paths_counts *c)
{
    const lanes_scene *s = job->scene;
    const int w = job->shade_k->lanes;
    double *stage = c->stage_seconds;
    packet_soa q;
    int next = 0, total = count * (s1 - s0), live = 0, nfree = st->size, finished = 0;
    for (int i = 0; i < st->size; i++) st->free_slots[i] = (uint32_t)(st->size - 1 - i), st->path[i].alive = false;
    while (next < total || live > 0) {
        /* generate: camera rays into the free slots, pixel by pixel within a sample */
        double t = lanes_render_clock();
        while (next < total && nfree > 0) {
            uint32_t slot = st->free_slots[--nfree];
            packet_lane *l = &st->path[slot];
            memset(l, 0, sizeof *l);
            int k = next++;
            l->pixel = tile_pixel[k % count];
            l->sample = (uint32_t)(s0 + k / count);
            l->tile_index = (uint32_t)(k % count);
            l->alive = l->after_delta = true;
            l->beta = v3(1, 1, 1);
            l->o = job->view.eye;
            l->d = camera_dir(job, l->pixel, l->sample);
            live++;
            c->paths++;
        }
        /* the extension rays of the live paths, in slot order */
        int nr = 0;
        for (int i = 0; i < st->size; i++) {
            packet_lane *l = &st->path[i];
            if (!l->alive) continue;
            st->rays[nr] = extension_ray(job, l->o, l->d);
            st->ray_slot[nr++] = (uint32_t)i;
        }
        /* the books: every path made is finished or in flight, one slot each */
        if (nr != live || next != finished + live || nfree + live != st->size) c->accounting_errors++;
        t = stage_clock(&stage[LANES_PATHS_STAGE_GENERATE], t);
        trace_rays(job, st->rays, (size_t)nr, st->hits);
        t = stage_clock(&stage[LANES_PATHS_STAGE_INTERSECT], t);
        /* hits: background, emission; what is left to shade */
        int ns = 0;
        for (int r = 0; r < nr; r++) {
            if (r + PREFETCH_AHEAD < nr) prefetch_hit(s, &st->hits[r + PREFETCH_AHEAD]);
            uint32_t slot = st->ray_slot[r];
            packet_lane *l = &st->path[slot];
            int depth = (int)l->ss_depth;
            c->by_depth[depth]++;
            const lanes_hit *h = &st->hits[r];
            l->alive = path_vertex(job, h, l->d, l->beta, l->after_delta, &l->sum, &l->sf, &l->material, &l->wo);
            if (l->alive) st->shade_slot[ns] = slot, st->shade_material[ns++] = l->material;
        }
        t = stage_clock(&stage[LANES_PATHS_STAGE_SHADE], t);
        lanes_error err;
        uint32_t nm = (uint32_t)(s->material_count ? s->material_count : 1);
        if (ns > 0 && lanes_sort_by_material(st->shade_material, (size_t)ns, nm, st->offsets, st->sorted, &err) != LANES_OK) {
            /* cannot happen: the materials are the scene's, checked at load */
            for (int i = 0; i < ns; i++) st->sorted[i] = (uint32_t)i;
        }
        t = stage_clock(&stage[LANES_PATHS_STAGE_SORT], t);
        /* shade in sorted order, W at a time within a material: the shadow
         * rays' BSDF values, then the extension rays */
        int nsh = 0;
        for (int first = 0; first < ns;) {
            uint32_t mat = st->shade_material[st->sorted[first]];
            int end = first;
            while (end < ns && st->shade_material[st->sorted[end]] == mat) end++;
            const lanes_bsdf *b = &job->bsdf[mat];
            bool delta = b->kind == LANES_BSDF_MIRROR || b->kind == LANES_BSDF_GLASS;
            for (int b0 = first; b0 < end; b0 += w) {
                int n = end - b0 < w ? end - b0 : w;
                float p_c[3 * LANES_MAX_W], albedo_c[3 * LANES_MAX_W];
                for (int i = 0; job->textured[mat] && i < n; i++) {
                    vec3 p = st->path[st->shade_slot[st->sorted[b0 + i]]].sf.p;
                    p_c[i] = p.x, p_c[n + i] = p.y, p_c[2 * n + i] = p.z;
                }
                const float *albedo = albedo_at(job, mat, (size_t)n, p_c, albedo_c);
                if (!delta) {
                    int lit = 0, lit_lane[LANES_MAX_W];
                    light_sample ls[LANES_MAX_W]; /* the lit lanes', compact */
                    for (int i = 0; i < n; i++) {
                        packet_lane *l = &st->path[st->shade_slot[st->sorted[b0 + i]]];
                        frame fr = surface_frame(&l->sf);
                        ls[lit] = light_pick(job, &l->sf, &fr, l->pixel, l->sample, l->ss_depth);
                        if (!ls[lit].active) continue;
                        soa_put(q.wo, w, lit, l->wo);
                        soa_put(q.wi, w, lit, ls[lit].wi_local);
                        lit_lane[lit++] = i;
                    }
                    if (lit > 0) {
                        /* the lit lanes packed: a compact call of lit items */
                        float wo_c[3 * LANES_MAX_W], wi_c[3 * LANES_MAX_W], albedo_lit[3 * LANES_MAX_W];
                        for (int k = 0; k < 3; k++)
                            for (int i = 0; i < lit; i++) {
                                wo_c[k * lit + i] = q.wo[k * w + i], wi_c[k * lit + i] = q.wi[k * w + i];
                                if (albedo) albedo_lit[k * lit + i] = albedo[k * n + lit_lane[i]];
                            }
                        job->shade_k->bsdf_eval(b, (size_t)lit, albedo ? albedo_lit : NULL, wo_c, wi_c, q.f, q.pdf);
                        count_shading(c, w, lit, false);
                        for (int j = 0; j < lit; j++) {
                            uint32_t slot = st->shade_slot[st->sorted[b0 + lit_lane[j]]];
                            packet_lane *l = &st->path[slot];
                            vec3 f = v3(q.f[j], q.f[lit + j], q.f[2 * lit + j]);
                            if (is_black(f)) continue;
                            c->shadow++;
                            if (!shadow_ray(job, &l->sf, &ls[j], &st->shadow[nsh])) continue;
                            st->shadow_slot[nsh] = slot;
                            st->shadow_add[nsh++] = v3_mul(l->beta, light_value(&ls[j], f));
                        }
                    }
                }
                float wo_c[3 * LANES_MAX_W], u_c[3 * LANES_MAX_W];
                for (int i = 0; i < n; i++) {
                    packet_lane *l = &st->path[st->shade_slot[st->sorted[b0 + i]]];
                    wo_c[i] = l->wo.x, wo_c[n + i] = l->wo.y, wo_c[2 * n + i] = l->wo.z;
                    for (int k = 0; k < 3; k++) u_c[k * n + i] = lanes_random01(l->pixel, l->sample, l->ss_depth, DIM_BSDF_1 + (uint32_t)k);
                }
                job->shade_k->bsdf_sample(b, (size_t)n, albedo, wo_c, u_c, q.wi, q.w, q.pdf, q.flags);
                count_shading(c, w, n, true);
                for (int i = 0; i < n; i++) {
                    packet_lane *l = &st->path[st->shade_slot[st->sorted[b0 + i]]];
                    l->pending_flags = q.flags[i];
                    for (int k = 0; k < 3; k++) l->pending_wi[k] = q.wi[k * n + i], l->pending_w[k] = q.w[k * n + i];
                }
            }
            first = end;
        }
        t = stage_clock(&stage[LANES_PATHS_STAGE_SHADE], t);
        /* the shadow stream, then each path's light before its next bounce
         * (the order single-1lane adds them in) */
        occluded_rays(job, st->shadow, (size_t)nsh, st->occluded);
        for (int i = 0; i < nsh; i++)
            if (!st->occluded[i]) {
                packet_lane *l = &st->path[st->shadow_slot[i]];
                l->sum = v3_add(l->sum, st->shadow_add[i]);
            }
        t = stage_clock(&stage[LANES_PATHS_STAGE_SHADOW], t);
        for (int i = 0; i < ns; i++) {
            uint32_t slot = st->shade_slot[i];
            packet_lane *l = &st->path[slot];
            bool go = (l->pending_flags & LANES_BSDF_VALID) != 0;
            if (go) {
                l->after_delta = (l->pending_flags & LANES_BSDF_DELTA) != 0;
                frame fr = surface_frame(&l->sf);
                go = continue_path(job, &l->sf, &fr, l->pending_wi, l->pending_w, (int)l->ss_depth, l->pixel,
                                   l->sample, &l->beta, &l->o, &l->d);
            }
            l->ss_depth++;
            if (!go || (int)l->ss_depth >= job->opt->depth) l->alive = false;
        }
        /* accumulate the finished paths and free their slots */
        for (int r = 0; r < nr; r++) {
            uint32_t slot = st->ray_slot[r];
            packet_lane *l = &st->path[slot];
            if (l->alive) continue;
            st->radiance[(l->sample - (uint32_t)s0) * (uint32_t)count + l->tile_index] = l->sum;
            st->free_slots[nfree++] = slot;
            live--;
            finished++;
            c->finished++;
        }
        if (next != finished + live || nfree + live != st->size) c->accounting_errors++;
        stage_clock(&stage[LANES_PATHS_STAGE_ACCUMULATE], t);
    }
}

static void render_tile_stream(const paths_job *job, const uint32_t *tile_pixel, int count, tile_sums *acc, paths_counts *c)
{
    stream_state *st = c->stream;
    for (int s0 = 0; s0 < job->opt->spp; s0 += STREAM_CHUNK_SAMPLES) {
        int s1 = s0 + STREAM_CHUNK_SAMPLES < job->opt->spp ? s0 + STREAM_CHUNK_SAMPLES : job->opt->spp;
        stream_chunk(job, st, tile_pixel, count, s0, s1, c);
        for (int sm = s0; sm < s1; sm++)
            for (int k = 0; k < count; k++) add_sample(acc, k, st->radiance[(sm - s0) * count + k]);
    }
}

/* ---- tiles and threads --------------------------------------------------- */

/* A 16x16 tile: its pixels' radiance summed over their samples in sample
 * order by the method, then averaged into the image. */
static void render_tile(const paths_job *job, int tile, paths_counts *c)
{
    int x0 = (tile % job->tiles_x) * 16, y0 = (tile / job->tiles_x) * 16;
    uint32_t tile_pixel[256];
    tile_sums acc;
    int count = 0;
    for (int y = y0; y < y0 + 16 && y < job->height; y++)
        for (int x = x0; x < x0 + 16 && x < job->width; x++)
            tile_pixel[count] = (uint32_t)y * (uint32_t)job->width + (uint32_t)x, acc.sum[count] = acc.sq[count] = v3(0, 0, 0),
            count++;
    const int spp = job->opt->spp;
    if (job->opt->method == LANES_PATHS_PACKET) {
        render_tile_packets(job, tile_pixel, count, &acc, c);
    } else if (job->opt->method == LANES_PATHS_STREAM) {
        render_tile_stream(job, tile_pixel, count, &acc, c);
    } else {
        for (int k = 0; k < count; k++)
            for (int s = 0; s < spp; s++) {
                add_sample(&acc, k, trace_path(job, job->view.eye, camera_dir(job, tile_pixel[k], (uint32_t)s),
                                               tile_pixel[k], (uint32_t)s, c));
                c->finished++;
            }
    }
    for (int k = 0; k < count; k++) {
        float *out = job->rgb + (size_t)tile_pixel[k] * 3, *out2 = job->rgb2 + (size_t)tile_pixel[k] * 3;
        out[0] = acc.sum[k].x / (float)spp, out[1] = acc.sum[k].y / (float)spp, out[2] = acc.sum[k].z / (float)spp;
        out2[0] = acc.sq[k].x / (float)spp, out2[1] = acc.sq[k].y / (float)spp, out2[2] = acc.sq[k].z / (float)spp;
    }
}

typedef struct {
    const paths_job *job;
    paths_counts *counts; /* per worker */
    atomic_int tiles_done;
    pthread_mutex_t progress_lock;
} paths_loop;

static void tile_task(void *ctx, size_t tile, int worker)
{
    paths_loop *l = ctx;
    render_tile(l->job, (int)tile, &l->counts[worker]);
    int done = atomic_fetch_add(&l->tiles_done, 1) + 1;
    const lanes_paths_options *o = l->job->opt;
    if (o->progress) {
        pthread_mutex_lock(&l->progress_lock);
        o->progress(o->progress_ctx, (double)done / ((double)l->job->tiles_x * (double)l->job->tiles_y));
        pthread_mutex_unlock(&l->progress_lock);
    }
}

static void free_job(paths_job *job)
{
    free(job->bsdf), free(job->texture), free(job->textured), free(job->area_light_quad), free(job->lights),
        free(job->light_cdf);
}

lanes_status lanes_paths_render(const lanes_scene *scene, const lanes_render_accel *accel,
                                const lanes_paths_options *opt, lanes_paths_result *out, lanes_error *err)
{
    memset(out, 0, sizeof *out);
    paths_job job;
    memset(&job, 0, sizeof job);
    job.scene = scene, job.accel = accel, job.opt = opt;
    job.trace_k = lanes_kernels_for(opt->isa);
    if (!job.trace_k || !lanes_isa_supported(opt->isa))
        return lanes_error_set(err, job.trace_k ? LANES_ERR_CPU_LACKS : LANES_ERR_NOT_COMPILED,
                               "paths: instruction set '%s' is not available", lanes_isa_name(opt->isa));
    if ((unsigned)opt->method >= LANES_PATHS_METHOD_COUNT)
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "paths: method %d unknown", (int)opt->method);
    if (opt->method == LANES_PATHS_STREAM &&
        (opt->stream < LANES_PATHS_MIN_STREAM || opt->stream > LANES_PATHS_MAX_STREAM || opt->stream % 16 != 0))
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "paths: stream size %d (%d..%d, a multiple of 16)", opt->stream,
                               LANES_PATHS_MIN_STREAM, LANES_PATHS_MAX_STREAM);
    if (opt->intersector && (!opt->intersector->trace || !opt->intersector->occluded))
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "paths: an intersector needs both its trace and occluded calls");
    if (opt->method == LANES_PATHS_STREAM && scene->material_count > LANES_SORT_MAX_MATERIALS)
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "paths: %zu materials; the stream's sort takes at most %u",
                               scene->material_count, LANES_SORT_MAX_MATERIALS);
    job.shade_k = opt->method == LANES_PATHS_SINGLE ? lanes_kernels_for(LANES_ISA_SCALAR) : job.trace_k;
    if (!job.shade_k)
        return lanes_error_set(err, LANES_ERR_NOT_COMPILED, "paths: the scalar set is not compiled in");
    if (accel->wide.width != job.trace_k->wide_width)
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "paths: %s traces a %d-wide BVH (have %d)",
                               job.trace_k->name, job.trace_k->wide_width, accel->wide.width);
    job.width = opt->width > 0 ? opt->width : scene->camera.width;
    job.height = opt->height > 0 ? opt->height : scene->camera.height;
    if (job.width <= 0 || job.height <= 0 || job.width > LANES_CAMERA_MAX_SIDE || job.height > LANES_CAMERA_MAX_SIDE)
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "paths: image size %dx%d out of range (1..%d)", job.width,
                               job.height, LANES_CAMERA_MAX_SIDE);
    if (opt->spp < 1 || opt->spp > LANES_PATHS_MAX_SPP)
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "paths: %d samples per pixel (1..%d)", opt->spp,
                               LANES_PATHS_MAX_SPP);
    if (opt->depth < 1 || opt->depth > LANES_PATHS_MAX_DEPTH)
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "paths: depth %d (1..%d)", opt->depth, LANES_PATHS_MAX_DEPTH);
    if (opt->accuracy < LANES_ACCURACY_FROM_SCENE || opt->accuracy >= LANES_ACCURACY_COUNT)
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "paths: accuracy mode %d unknown", (int)opt->accuracy);
    for (int k = 0; opt->uniform_background && k < 3; k++)
        if (!(opt->background[k] >= 0.0f && opt->background[k] <= 3.4e38f))
            return lanes_error_set(err, LANES_ERR_BAD_INPUT, "paths: background %g is not a radiance (finite, >= 0)",
                                   (double)opt->background[k]);
    lanes_scene_plan plan;
    lanes_scene_plan_make(scene, opt->accuracy, &plan);
    lanes_status fits = lanes_scene_plan_check(&plan, err);
    if (fits != LANES_OK) return fits;
    job.accuracy = plan.accuracy;
    job.rcp = lanes_accuracy_precision(plan.accuracy).rcp;
    job.eps = lanes_scene_epsilon(scene);
    job.view = lanes_view_make(&scene->camera, job.width, job.height);

    size_t nm = scene->material_count ? scene->material_count : 1;
    job.bsdf = calloc(nm, sizeof *job.bsdf);
    job.texture = calloc(nm, sizeof *job.texture);
    job.textured = calloc(nm, sizeof *job.textured);
    job.area_light_quad = calloc(nm, sizeof *job.area_light_quad);
    if (!job.bsdf || !job.texture || !job.textured || !job.area_light_quad || !prepare_lights(&job)) {
        free_job(&job);
        return lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY, "paths: out of memory");
    }
    for (size_t i = 0; i < scene->material_count; i++) {
        job.bsdf[i] = bsdf_of(&scene->materials[i]);
        job.textured[i] = scene->materials[i].texture != LANES_MAT_TEXTURE_NONE;
        if (job.textured[i]) job.texture[i] = texture_of(&scene->materials[i]);
        job.area_light_quad[i] = strncmp(scene->materials[i].name, "@area_light_", 12) == 0;
    }
    job.rgb = calloc((size_t)job.width * (size_t)job.height * 3, sizeof(float));
    job.rgb2 = calloc((size_t)job.width * (size_t)job.height * 3, sizeof(float));
    int threads = lanes_parallel_threads(opt->threads);
    paths_counts *counts = calloc((size_t)threads, sizeof *counts);
    stream_state *streams = opt->method == LANES_PATHS_STREAM ? calloc((size_t)threads, sizeof *streams) : NULL;
    bool ok = job.rgb && job.rgb2 && counts && (opt->method != LANES_PATHS_STREAM || streams);
    for (int i = 0; ok && streams && i < threads; i++) {
        ok = stream_alloc(&streams[i], opt->stream, scene->material_count, opt->spp);
        counts[i].stream = &streams[i];
    }
    if (!ok) {
        for (int i = 0; streams && i < threads; i++) stream_free(&streams[i]);
        free(streams), free(job.rgb), free(job.rgb2), free(counts), free_job(&job);
        return lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY, "paths: out of memory for the image or the streams");
    }
    if (streams) out->stream_bytes = stream_bytes(opt->stream, scene->material_count, opt->spp);
    job.tiles_x = (job.width + 15) / 16;
    job.tiles_y = (job.height + 15) / 16;
    double t0 = lanes_render_clock();
    paths_loop loop = {&job, counts, 0, PTHREAD_MUTEX_INITIALIZER};
    lanes_parallel_for(threads, (size_t)job.tiles_x * (size_t)job.tiles_y, tile_task, &loop);
    pthread_mutex_destroy(&loop.progress_lock);
    out->seconds = lanes_render_clock() - t0;
    for (int i = 0; i < threads; i++) {
        out->paths += counts[i].paths;
        out->paths_finished += counts[i].finished;
        out->accounting_errors += counts[i].accounting_errors;
        out->shadow_rays += counts[i].shadow;
        out->shade_calls += counts[i].shade_calls;
        out->shade_slots += counts[i].shade_slots;
        out->shade_live += counts[i].shade_live;
        out->sample_calls += counts[i].sample_calls;
        out->sample_slots += counts[i].sample_slots;
        out->sample_live += counts[i].sample_live;
        for (int d = 0; d <= LANES_PATHS_MAX_DEPTH; d++) out->rays_by_depth[d] += counts[i].by_depth[d];
        for (int k = 0; k < LANES_PATHS_STAGE_COUNT; k++) out->stage_seconds[k] += counts[i].stage_seconds[k];
    }
    for (int i = 0; streams && i < threads; i++) stream_free(&streams[i]);
    free(streams);
    free(counts);
    free_job(&job);
    out->rgb = job.rgb;
    out->rgb2 = job.rgb2;
    out->width = job.width;
    out->height = job.height;
    return LANES_OK;
}

void lanes_paths_result_free(lanes_paths_result *r)
{
    free(r->rgb), free(r->rgb2);
    memset(r, 0, sizeof *r);
}
