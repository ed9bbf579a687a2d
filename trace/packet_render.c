/* The Whitted renderer on ray packets (see packet_render.h). */
#define _DEFAULT_SOURCE /* sysconf, clock_gettime */
#include "trace/packet_render.h"

#include "build/camera.h"
#include "build/grow_array.h"
#include "build/parallel.h"
#include "trace/scene_plan.h"
#include "trace/shading.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

static const char *const queue_names[LANES_QUEUE_COUNT] = {"none", "MAX", "CORNER", "arrival"};
static const char *const ray_type_names[LANES_RAY_TYPE_COUNT] = {"primary", "shadow", "specular"};

const char *lanes_queue_name(lanes_queue_heuristic q)
{
    return q >= 0 && q < LANES_QUEUE_COUNT ? queue_names[q] : "?";
}

int lanes_queue_from_name(const char *name)
{
    for (int i = 0; name && i < LANES_QUEUE_COUNT; i++)
        if (strcasecmp(name, queue_names[i]) == 0) return i;
    return -1;
}

const char *lanes_ray_type_name(lanes_ray_type t)
{
    return t >= 0 && t < LANES_RAY_TYPE_COUNT ? ray_type_names[t] : "?";
}

void lanes_packet_render_default_options(lanes_packet_render_options *o)
{
    memset(o, 0, sizeof *o);
    lanes_render_default_options(&o->base);
    o->scheme = LANES_PACKET_PARTITION;
    o->queue = LANES_QUEUE_MAX;
    o->queue_min = 1024;
    o->packet_size = LANES_PACKET_MAX_RAYS;
    o->frustum = true;
    o->corner_test = true;
    /* Off by default: with leaves of at most 4 triangles, rebuilding a
     * frustum from the live rays costs more than the triangle tests it saves
     * (dragon, primary and shadow packets, avx2, callgrind: 1.29e9
     * instructions in the packet traversal with it, 0.89e9 without). The
     * thesis' leaves were larger. */
    o->leaf_frustum = false;
}

/* A ray waiting for its packet: camera and specular rays carry the weight
 * of what they bring back to their pixel. */
typedef struct {
    vec3 o, d, weight;
    uint32_t pixel, seed;
} pending_ray;

typedef struct {
    vec3 o, d;
    float tnear, tfar;
    vec3 add;
    uint32_t pixel, light;
} pending_shadow;

typedef struct {
    pending_ray *a;
    size_t n, cap;
} ray_list;

typedef struct {
    pending_shadow *a;
    size_t n, cap;
} shadow_list;


static bool push_ray(ray_list *l, pending_ray r)
{
    if (!lanes_grow_array((void **)&l->a, &l->cap, l->n + 1, sizeof r)) return false;
    l->a[l->n++] = r;
    return true;
}

static bool push_shadow(shadow_list *l, pending_shadow r)
{
    if (!lanes_grow_array((void **)&l->a, &l->cap, l->n + 1, sizeof r)) return false;
    l->a[l->n++] = r;
    return true;
}

/* Shared, read-only state of one render. */
typedef struct {
    const lanes_scene *scene;
    const lanes_render_accel *accel;
    const lanes_packet_render_options *opt; /* = &resolved */
    lanes_packet_render_options resolved;   /* the caller's, with the accuracy mode resolved */
    const lanes_kernels *k;
    float eps;
    lanes_scene_plan plan;
    lanes_view view;
    int width, height, side, qx, qy;     /* primary packets: side x side pixels, qx x qy of them */
    uint32_t *quad_order;                /* quadrants in Hilbert order */
    size_t quads;
    uint32_t *subtree;                   /* triangles under each BVH2 node; only with a specular pass */
    float root_lo[3], root_hi[3];
    float *rgb;
    atomic_int quads_done;
    pthread_mutex_t progress_lock;
} job_t;

/* Per-thread state. */
typedef struct {
    job_t *job;
    lanes_rays pk;
    uint32_t *prim;
    float *u, *v;
    uint8_t *occluded;
    lanes_hit *hits;
    ray_list queue[2];   /* this bounce's specular rays, and the next's */
    shadow_list shadows;
    lanes_shadow_ray *shadow_tmp;
    uint64_t *keys;      /* sort keys for packet formation */
    size_t keys_cap;
    lanes_packet_metrics m;
    uint64_t camera_rays, shadow_rays, secondary_rays;
    uint64_t by_depth[LANES_MAX_DEPTH + 1];
    bool failed;
    size_t first_quad, end_quad;
} worker_t;

/* Hilbert index of (x, y) on a side x side grid, side a power of two. */
static uint64_t hilbert_index(uint32_t side, uint32_t x, uint32_t y)
{
    uint64_t d = 0;
    for (uint32_t s = side / 2; s > 0; s /= 2) {
        uint32_t rx = (x & s) > 0, ry = (y & s) > 0;
        d += (uint64_t)s * s * ((3 * rx) ^ ry);
        if (ry == 0) {
            if (rx == 1) {
                x = s - 1 - x;
                y = s - 1 - y;
            }
            uint32_t t = x;
            x = y;
            y = t;
        }
    }
    return d;
}

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* Traces pk (count rays filled in) as one packet; hits[i] gets the results. */
static void trace_filled_packet(worker_t *w, lanes_ray_type type, bool occlusion)
{
    const job_t *job = w->job;
    const lanes_packet_render_options *opt = job->opt;
    size_t n = w->pk.count;
    lanes_frustum f;
    lanes_packet_options po = {opt->scheme, opt->base.accuracy, NULL, opt->corner_test,
                               opt->leaf_frustum, occlusion};
    job->k->rays_prepare(&w->pk, lanes_accuracy_precision(opt->base.accuracy).rcp);
    if (opt->frustum) {
        job->k->frustum_build(&w->pk, NULL, n, &f);
        po.frustum = &f;
    }
    for (size_t i = 0; i < n; i++) {
        w->prim[i] = LANES_NO_HIT;
        w->occluded[i] = 0;
    }
    lanes_packet_stats *st = opt->count ? &w->m.stats[type] : NULL;
    uint64_t slots0 = st ? st->box_ops.lane_slots + st->tri_ops.lane_slots : 0;
    uint64_t live0 = st ? st->box_ops.active_lanes + st->tri_ops.active_lanes : 0;
    job->k->trace_packet(&job->accel->bvh2, &po, &w->pk, w->prim, w->u, w->v, w->occluded, st);
    if (st) {
        uint64_t slots = st->box_ops.lane_slots + st->tri_ops.lane_slots - slots0;
        uint64_t live = st->box_ops.active_lanes + st->tri_ops.active_lanes - live0;
        if (slots) w->m.packet_util_sum[type] += (double)live / (double)slots;
    }
    w->m.packets[type]++;
    w->m.rays[type] += n;
    w->m.packets_of_size[type][n]++;
    if (!occlusion)
        for (size_t i = 0; i < n; i++)
            w->hits[i] = (lanes_hit){w->pk.tfar[i], w->u[i], w->v[i], w->prim[i]};
}

static void set_ray(lanes_rays *pk, size_t i, vec3 o, vec3 d, float tnear, float tfar)
{
    pk->ox[i] = o.x, pk->oy[i] = o.y, pk->oz[i] = o.z;
    pk->dx[i] = d.x, pk->dy[i] = d.y, pk->dz[i] = d.z;
    pk->tnear[i] = tnear, pk->tfar[i] = tfar;
}

static void add_pixel(const job_t *job, uint32_t pixel, vec3 c)
{
    float *p = job->rgb + (size_t)pixel * 3;
    p[0] += c.x, p[1] += c.y, p[2] += c.z;
}

/* What a camera or specular ray found: light for its pixel, shadow rays,
 * and the next bounce's rays. */
static void shade_hit(worker_t *w, const pending_ray *r, const lanes_hit *h, int depth)
{
    const job_t *job = w->job;
    const lanes_scene *s = job->scene;
    if (h->prim == LANES_NO_HIT) {
        add_pixel(job, r->pixel, v3_mul(r->weight, lanes_background(r->d)));
        return;
    }
    lanes_surface sf = job->plan.hit_geometry ? lanes_surface_at(s, h, r->d) : lanes_surface_material(s, h);
    switch (lanes_material_whitted_kind(sf.m->kind)) {
    case LANES_MAT_EMISSIVE:
        add_pixel(job, r->pixel, v3_mul(r->weight, v3_load(sf.m->emission)));
        break;
    case LANES_MAT_DIFFUSE: {
        vec3 ambient;
        int n = lanes_diffuse_light(s, &sf, r->weight, r->seed, job->opt->base.accuracy, job->eps, job->opt->base.area_samples,
                                    w->shadow_tmp, &ambient);
        add_pixel(job, r->pixel, v3_add(ambient, v3_mul(r->weight, v3_load(sf.m->emission))));
        for (int i = 0; i < n; i++) {
            const lanes_shadow_ray *sr = &w->shadow_tmp[i];
            /* Shadow rays toward a point light start at the light, so a
             * packet's rays share their origin (Wu 3.4.2). The segment is
             * the same; the far end stops at the offset surface point.
             * Not in robust mode: there the offset is a few ulps of the
             * hit point, below the rounding of a t measured from the
             * light, and the reversed ray would hit the surface it is
             * meant to end above. */
            pending_shadow ps;
            if (sr->light < s->point_light_count && job->opt->base.accuracy != LANES_ACCURACY_ROBUST) {
                float dist = sr->tfar / (1.0f - 1e-4f);
                ps = (pending_shadow){v3_load(s->point_lights[sr->light].position), v3_scale(sr->d, -1.0f),
                                      dist * 1e-4f, dist, sr->add, r->pixel, sr->light};
            } else {
                ps = (pending_shadow){sr->o, sr->d, 0.0f, sr->tfar, sr->add, r->pixel, sr->light};
            }
            if (!push_shadow(&w->shadows, ps)) w->failed = true;
            w->m.shadow_made++;
        }
        break;
    }
    case LANES_MAT_MIRROR:
    case LANES_MAT_GLASS: {
        if (depth >= job->opt->base.max_depth) break;
        lanes_bounce_ray b[2];
        int n = lanes_specular_rays(&sf, r->d, r->weight, r->seed, job->opt->base.accuracy, job->eps, b);
        for (int i = 0; i < n; i++)
            if (!push_ray(&w->queue[1], (pending_ray){b[i].o, b[i].d, b[i].weight, r->pixel, b[i].seed}))
                w->failed = true;
        w->m.specular_made[depth + 1] += (uint64_t)n;
        break;
    }
    case LANES_MAT_CONDUCTOR:
    case LANES_MAT_PLASTIC:
        break; /* not a Whitted kind: lanes_material_whitted_kind maps them */
    }
}

/* Primary packet of one quadrant: rays laid out group by group, each group
 * a 1x1, 2x2, 2x4 or 4x4 pixel tile, so one SIMD test covers neighbours;
 * pixels off the image become inactive padding rays. */
static void primary_packet(worker_t *w, uint32_t quad, int sample)
{
    const job_t *job = w->job;
    int W = job->k->lanes;
    int gw = W == 16 ? 4 : (W >= 4 ? W / 2 : 1), gh = W / gw;
    int x0 = (int)(quad % (uint32_t)job->qx) * job->side, y0 = (int)(quad / (uint32_t)job->qx) * job->side;
    pending_ray rays[LANES_PACKET_MAX_RAYS];
    size_t n = 0;
    int spp = job->opt->base.spp, strata = (int)ceilf(sqrtf((float)spp));
    for (int gy = 0; gy < job->side; gy += gh)
        for (int gx = 0; gx < job->side; gx += gw)
            for (int py = 0; py < gh; py++)
                for (int px = 0; px < gw; px++) {
                    int x = x0 + gx + px, y = y0 + gy + py;
                    if (x >= job->width || y >= job->height) {
                        set_ray(&w->pk, n, v3(0, 0, 0), v3(0, 0, 1), INFINITY, -INFINITY);
                        rays[n++].pixel = UINT32_MAX;
                        continue;
                    }
                    uint32_t seed = ((uint32_t)y * 65536u + (uint32_t)x) * 64u + (uint32_t)sample;
                    float sx = 0.5f, sy = 0.5f;
                    if (spp > 1) {
                        sx = ((float)(sample % strata) + lanes_hash01(seed, 1, 0)) / (float)strata;
                        sy = ((float)(sample / strata % strata) + lanes_hash01(seed, 2, 0)) / (float)strata;
                    }
                    vec3 d = lanes_view_dir(&job->view, (float)x + sx, (float)y + sy);
                    set_ray(&w->pk, n, job->view.eye, d, 0.0f, INFINITY);
                    rays[n++] = (pending_ray){job->view.eye, d, v3(1, 1, 1),
                                              (uint32_t)y * (uint32_t)job->width + (uint32_t)x, seed};
                }
    w->pk.count = n;
    trace_filled_packet(w, LANES_RAYS_PRIMARY, false);
    for (size_t i = 0; i < n; i++) {
        if (rays[i].pixel == UINT32_MAX) continue;
        w->camera_rays++;
        shade_hit(w, &rays[i], &w->hits[i], 0);
    }
}

/* Set of a direction: dominant axis and sign (6 sets) or octant (8). */
static uint32_t direction_set(vec3 d, bool octant)
{
    if (octant) return (d.x < 0.0f) | ((d.y < 0.0f) << 1) | ((d.z < 0.0f) << 2);
    float ax = fabsf(d.x), ay = fabsf(d.y), az = fabsf(d.z);
    int k = ax >= ay ? (ax >= az ? 0 : 2) : (ay >= az ? 1 : 2);
    float c = k == 0 ? d.x : (k == 1 ? d.y : d.z);
    return (uint32_t)(2 * k + (c < 0.0f));
}

/* The queue node of an origin: down the BVH2 while the child nearest to the
 * origin still holds queue_min triangles (the deepest such node). */
static uint32_t queue_node(const job_t *job, vec3 o)
{
    const lanes_bvh2 *b = &job->accel->bvh2;
    uint32_t node = 0;
    float p[3] = {o.x, o.y, o.z};
    for (;;) {
        const lanes_bvh2_node *nd = &b->nodes[node];
        if (nd->count > 0) return node;
        float best = INFINITY;
        uint32_t pick = nd->first;
        for (uint32_t c = nd->first; c <= nd->first + 1; c++) {
            float d2 = 0.0f;
            for (int a = 0; a < 3; a++) {
                float e = p[a] < b->nodes[c].min[a] ? b->nodes[c].min[a] - p[a]
                          : (p[a] > b->nodes[c].max[a] ? p[a] - b->nodes[c].max[a] : 0.0f);
                d2 += e * e;
            }
            if (d2 < best) best = d2, pick = c;
        }
        if (job->subtree[pick] < (uint32_t)job->opt->queue_min) return node;
        node = pick;
    }
}

/* Cell of a ray on a 16 x 16 grid over the root box face it leaves by
 * (along its dominant axis), in Hilbert order: neighbouring cells, similar
 * rays (Wu 3.4.5, "Ray Reordering"). */
static uint32_t exit_cell(const job_t *job, vec3 o, vec3 d)
{
    float p[3] = {o.x, o.y, o.z}, q[3] = {d.x, d.y, d.z};
    int k = fabsf(q[0]) >= fabsf(q[1]) ? (fabsf(q[0]) >= fabsf(q[2]) ? 0 : 2) : (fabsf(q[1]) >= fabsf(q[2]) ? 1 : 2);
    float plane = q[k] < 0.0f ? job->root_lo[k] : job->root_hi[k];
    float t = (plane - p[k]) / q[k];
    uint32_t cell[2];
    for (int j = 0; j < 2; j++) {
        int a = (k + 1 + j) % 3;
        float ext = job->root_hi[a] - job->root_lo[a];
        float x = ext > 0.0f ? (p[a] + t * q[a] - job->root_lo[a]) / ext : 0.0f;
        x = x < 0.0f ? 0.0f : (x > 0.999f ? 0.999f : x);
        cell[j] = (uint32_t)(x * 16.0f);
    }
    return (uint32_t)hilbert_index(16, cell[0], cell[1]);
}

static bool ensure_keys(worker_t *w, size_t n)
{
    return lanes_grow_array((void **)&w->keys, &w->keys_cap, n, sizeof(uint64_t));
}

/* Sorts the rays into packets and traces them. Sort keys, high bits to low:
 * queued: queue node * 8 + direction set (32 bits), exit cell (8), ray (24);
 * global division: direction set (8 bits), order (32), ray (24), where the
 * order is a hash of the ray's index (none) or zero (arrival). A packet
 * takes consecutive rays of one group: key >> GROUP_SHIFT. */
static int group_shift(lanes_queue_heuristic h)
{
    return h == LANES_QUEUE_MAX || h == LANES_QUEUE_CORNER ? 32 : 56;
}

static uint64_t shuffle_order(uint64_t i)
{
    uint64_t x = (i + 1) * 0x9E3779B97F4A7C15ull;
    x ^= x >> 29;
    x *= 0xBF58476D1CE4E5B9ull;
    x ^= x >> 32;
    return x & 0xffffffffu;
}

static void trace_specular(worker_t *w, int depth)
{
    const job_t *job = w->job;
    ray_list *q = &w->queue[0];
    size_t n = q->n;
    if (n == 0) return;
    if (n >= (1u << 24) || !ensure_keys(w, n)) {
        w->failed = true; /* more rays than the sort key has room for, or out of memory */
        return;
    }
    lanes_queue_heuristic h = job->opt->queue;
    bool queued = h == LANES_QUEUE_MAX || h == LANES_QUEUE_CORNER;
    int shift = group_shift(h);
    for (size_t i = 0; i < n; i++) {
        const pending_ray *r = &q->a[i];
        uint64_t set = direction_set(r->d, h == LANES_QUEUE_CORNER);
        if (queued) {
            uint64_t node = queue_node(job, r->o);
            uint64_t cell = exit_cell(job, r->o, r->d);
            w->keys[i] = ((node * 8 + set) << 32) | (cell << 24) | (uint64_t)i;
        } else {
            uint64_t order = h == LANES_QUEUE_NONE ? shuffle_order(i) : 0;
            w->keys[i] = (set << 56) | (order << 24) | (uint64_t)i;
        }
    }
    qsort(w->keys, n, sizeof(uint64_t), cmp_u64);
    size_t size = (size_t)job->opt->packet_size;
    pending_ray batch[LANES_PACKET_MAX_RAYS];
    for (size_t start = 0; start < n;) {
        uint64_t group = w->keys[start] >> shift;
        size_t end = start;
        while (end < n && end - start < size && (w->keys[end] >> shift) == group) end++;
        for (size_t i = start; i < end; i++) {
            const pending_ray *r = &q->a[w->keys[i] & 0xffffffu];
            batch[i - start] = *r;
            set_ray(&w->pk, i - start, r->o, r->d, 0.0f, INFINITY);
        }
        w->pk.count = end - start;
        trace_filled_packet(w, LANES_RAYS_SPECULAR, false);
        w->by_depth[depth] += end - start;
        w->m.specular_traced[depth] += end - start;
        for (size_t i = 0; i < end - start; i++) {
            w->secondary_rays++;
            shade_hit(w, &batch[i], &w->hits[i], depth);
        }
        start = end;
    }
}

/* Shadow packets: per light, split into the 8 direction octants, in the
 * order the rays were made (which follows the primary packets' Hilbert
 * order). */
static void trace_shadows(worker_t *w)
{
    shadow_list *sl = &w->shadows;
    size_t n = sl->n;
    if (n == 0) return;
    if (!ensure_keys(w, n) || n >= (1u << 31)) {
        w->failed = true;
        return;
    }
    for (size_t i = 0; i < n; i++) {
        uint64_t group = (uint64_t)sl->a[i].light * 8 + direction_set(sl->a[i].d, true);
        w->keys[i] = (group << 32) | (uint64_t)i;
    }
    qsort(w->keys, n, sizeof(uint64_t), cmp_u64);
    size_t size = (size_t)w->job->opt->packet_size;
    for (size_t start = 0; start < n;) {
        uint64_t group = w->keys[start] >> 32;
        size_t end = start;
        while (end < n && end - start < size && (w->keys[end] >> 32) == group) end++;
        for (size_t i = start; i < end; i++) {
            const pending_shadow *s = &sl->a[w->keys[i] & 0xffffffffu];
            set_ray(&w->pk, i - start, s->o, s->d, s->tnear, s->tfar);
        }
        w->pk.count = end - start;
        trace_filled_packet(w, LANES_RAYS_SHADOW, true);
        w->m.shadow_traced += end - start;
        for (size_t i = start; i < end; i++) {
            const pending_shadow *s = &sl->a[w->keys[i] & 0xffffffffu];
            w->shadow_rays++;
            if (!w->occluded[i - start]) add_pixel(w->job, s->pixel, s->add);
        }
        start = end;
    }
    sl->n = 0;
}

static void worker_main(worker_t *w)
{
    const job_t *job = w->job;
    for (int sample = 0; sample < job->opt->base.spp && !w->failed; sample++) {
        for (size_t qi = w->first_quad; qi < w->end_quad; qi++) {
            primary_packet(w, job->quad_order[qi], sample);
            if (job->opt->base.progress && sample == job->opt->base.spp - 1) {
                int done = atomic_fetch_add(&w->job->quads_done, 1) + 1;
                pthread_mutex_lock(&w->job->progress_lock);
                job->opt->base.progress(job->opt->base.progress_ctx, (double)done / (double)job->quads);
                pthread_mutex_unlock(&w->job->progress_lock);
            }
        }
        /* Bounces in order: rays of one bounce never share a packet with
         * another's (Wu 3.2). */
        for (int depth = 1; depth <= job->opt->base.max_depth && w->queue[1].n > 0; depth++) {
            ray_list t = w->queue[0];
            w->queue[0] = w->queue[1];
            w->queue[1] = t;
            w->queue[1].n = 0;
            trace_specular(w, depth);
        }
        w->queue[1].n = 0;
        trace_shadows(w);
    }
}

static void share_task(void *ctx, size_t share, int worker)
{
    (void)worker;
    worker_main((worker_t *)ctx + share);
}

static bool worker_init(worker_t *w, job_t *job)
{
    memset(w, 0, sizeof *w);
    w->job = job;
    size_t cap = LANES_PACKET_MAX_RAYS;
    if (!lanes_rays_alloc(&w->pk, cap)) return false;
    w->prim = calloc(cap + LANES_MAX_W, sizeof *w->prim);
    w->u = calloc(cap + LANES_MAX_W, sizeof *w->u);
    w->v = calloc(cap + LANES_MAX_W, sizeof *w->v);
    w->occluded = calloc(cap + LANES_MAX_W, 1);
    w->hits = calloc(cap, sizeof *w->hits);
    w->shadow_tmp = calloc((size_t)lanes_max_shadow_rays(job->scene, job->opt->base.area_samples) + 1,
                           sizeof *w->shadow_tmp);
    return w->prim && w->u && w->v && w->occluded && w->hits && w->shadow_tmp;
}

static void worker_free(worker_t *w)
{
    lanes_rays_free(&w->pk);
    free(w->prim), free(w->u), free(w->v), free(w->occluded), free(w->hits), free(w->shadow_tmp);
    free(w->queue[0].a), free(w->queue[1].a), free(w->shadows.a), free(w->keys);
}

/* Triangles under every node, children before parents by a post-order walk. */
static uint32_t *subtree_counts(const lanes_bvh2 *b)
{
    uint32_t *count = calloc(b->node_count ? b->node_count : 1, sizeof *count);
    uint32_t *stack = malloc(2 * (b->node_count + 1) * sizeof *stack);
    if (!count || !stack) {
        free(count), free(stack);
        return NULL;
    }
    size_t sp = 0;
    if (b->node_count) stack[sp++] = 0;
    while (sp > 0) {
        uint32_t top = stack[sp - 1];
        const lanes_bvh2_node *nd = &b->nodes[top & 0x7fffffffu];
        if (nd->count > 0) {
            count[top & 0x7fffffffu] = nd->count;
            sp--;
        } else if (top & 0x80000000u) {
            uint32_t i = top & 0x7fffffffu;
            count[i] = count[nd->first] + count[nd->first + 1];
            sp--;
        } else {
            stack[sp - 1] = top | 0x80000000u;
            stack[sp++] = nd->first;
            stack[sp++] = nd->first + 1;
        }
    }
    free(stack);
    return count;
}

int lanes_packet_min_size(int lanes)
{
    int n = 1;
    while (n < lanes) n *= 4;
    return n;
}

lanes_status lanes_packet_render(const lanes_scene *scene, const lanes_render_accel *accel,
                                 const lanes_packet_render_options *opt, lanes_render_result *out,
                                 lanes_packet_metrics *metrics, lanes_error *err)
{
    memset(out, 0, sizeof *out);
    if (metrics) memset(metrics, 0, sizeof *metrics);
    job_t job;
    memset(&job, 0, sizeof job);
    job.scene = scene;
    job.accel = accel;
    job.opt = opt;
    job.k = lanes_kernels_for(opt->base.isa);
    if (!job.k || !lanes_isa_supported(opt->base.isa)) {
        return lanes_error_set(err, job.k ? LANES_ERR_CPU_LACKS : LANES_ERR_NOT_COMPILED,
                               "render: instruction set '%s' is not available",
                               lanes_isa_name(opt->base.isa));
    }
    int min_packet = lanes_packet_min_size(job.k->lanes);
    if (opt->packet_size < min_packet || opt->packet_size > LANES_PACKET_MAX_RAYS) {
        return lanes_error_set(
            err, LANES_ERR_BAD_INPUT,
            "render: packet size %d out of range (%d..%d at %d lanes: primary packets are square "
            "tiles of a power-of-two side, and the largest one of at most that many rays must "
            "hold a whole %d-lane group)",
            opt->packet_size, min_packet, LANES_PACKET_MAX_RAYS, job.k->lanes, job.k->lanes);
    }
    if (opt->queue_min < 1) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "render: queue size %d below 1", opt->queue_min);
    }
    int side = 1; /* the primary packets' tile: the largest power-of-two square that fits */
    while ((side * 2) * (side * 2) <= opt->packet_size) side *= 2;
    job.width = opt->base.width > 0 ? opt->base.width : scene->camera.width;
    job.height = opt->base.height > 0 ? opt->base.height : scene->camera.height;
    if (job.width <= 0 || job.height <= 0 || job.width > LANES_CAMERA_MAX_SIDE || job.height > LANES_CAMERA_MAX_SIDE ||
        opt->base.spp < 1 || opt->base.spp > 65536 || opt->base.max_depth < 0 ||
        opt->base.max_depth > LANES_MAX_DEPTH) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT,
                               "render: image size %dx%d, %d samples per pixel or depth %d out of range "
                               "(1..%d, 1..65536, 0..%d)",
                               job.width, job.height, opt->base.spp, opt->base.max_depth, LANES_CAMERA_MAX_SIDE,
                               LANES_MAX_DEPTH);
    }
    if (accel->bvh2.node_count == 0) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "render: the scene has no triangles");
    }
    job.side = side;
    job.qx = (job.width + side - 1) / side;
    job.qy = (job.height + side - 1) / side;
    job.quads = (size_t)job.qx * (size_t)job.qy;
    if (opt->base.accuracy < LANES_ACCURACY_FROM_SCENE || opt->base.accuracy >= LANES_ACCURACY_COUNT) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "render: accuracy mode %d unknown",
                               (int)opt->base.accuracy);
    }
    lanes_scene_plan_make(scene, opt->base.accuracy, &job.plan);
    lanes_status fits = lanes_scene_plan_check(&job.plan, err);
    if (fits != LANES_OK) return fits;
    job.resolved = *opt;
    job.resolved.base.accuracy = job.plan.accuracy;
    job.opt = &job.resolved;
    job.eps = lanes_scene_epsilon(scene);
    job.view = lanes_view_make(&scene->camera, job.width, job.height);
    memcpy(job.root_lo, accel->bvh2.nodes[0].min, sizeof job.root_lo);
    memcpy(job.root_hi, accel->bvh2.nodes[0].max, sizeof job.root_hi);

    /* Quadrants in Hilbert order over the smallest power-of-two grid. */
    uint32_t grid = 1;
    while (grid < (uint32_t)job.qx || grid < (uint32_t)job.qy) grid *= 2;
    uint64_t *order = malloc(job.quads * sizeof *order);
    job.quad_order = malloc(job.quads * sizeof *job.quad_order);
    /* the specular queues' nodes: not needed when no ray is reflected */
    job.subtree = job.plan.specular_pass ? subtree_counts(&accel->bvh2) : NULL;
    job.rgb = calloc((size_t)job.width * (size_t)job.height * 3, sizeof(float));
    bool ok = order && job.quad_order && (job.subtree || !job.plan.specular_pass) && job.rgb;
    if (ok) {
        for (uint32_t q = 0; q < job.quads; q++) {
            uint32_t x = q % (uint32_t)job.qx, y = q / (uint32_t)job.qx;
            order[q] = (hilbert_index(grid, x, y) << 32) | q;
        }
        qsort(order, job.quads, sizeof *order, cmp_u64);
        for (size_t q = 0; q < job.quads; q++) job.quad_order[q] = (uint32_t)(order[q] & 0xffffffffu);
    }
    free(order);

    int threads = lanes_parallel_threads(opt->base.threads);
    if ((size_t)threads > job.quads) threads = (int)job.quads;
    worker_t *workers = ok ? calloc((size_t)threads, sizeof *workers) : NULL;
    int inited = 0;
    ok = ok && workers;
    for (int i = 0; ok && i < threads; i++) {
        ok = worker_init(&workers[i], &job);
        inited = i + 1;
        /* contiguous runs of the Hilbert order keep each thread's queues coherent */
        workers[i].first_quad = job.quads * (size_t)i / (size_t)threads;
        workers[i].end_quad = job.quads * (size_t)(i + 1) / (size_t)threads;
    }
    if (ok) {
        pthread_mutex_init(&job.progress_lock, NULL);
        double t0 = lanes_render_clock();
        /* one item per worker's share (whichever thread runs it) */
        lanes_parallel_for(threads, (size_t)threads, share_task, workers);
        out->seconds = lanes_render_clock() - t0;
        pthread_mutex_destroy(&job.progress_lock);
    }
    for (int i = 0; i < inited; i++) {
        worker_t *w = &workers[i];
        ok = ok && !w->failed;
        out->camera_rays += w->camera_rays;
        out->shadow_rays += w->shadow_rays;
        out->secondary_rays += w->secondary_rays;
        for (int d = 0; d <= LANES_MAX_DEPTH; d++) out->secondary_by_depth[d] += w->by_depth[d];
        if (metrics) {
            metrics->shadow_made += w->m.shadow_made;
            metrics->shadow_traced += w->m.shadow_traced;
            for (int d = 0; d <= LANES_MAX_DEPTH; d++) {
                metrics->specular_made[d] += w->m.specular_made[d];
                metrics->specular_traced[d] += w->m.specular_traced[d];
            }
            for (int t = 0; t < LANES_RAY_TYPE_COUNT; t++) {
                metrics->rays[t] += w->m.rays[t];
                metrics->packets[t] += w->m.packets[t];
                metrics->packet_util_sum[t] += w->m.packet_util_sum[t];
                for (int k = 0; k <= LANES_PACKET_MAX_RAYS; k++)
                    metrics->packets_of_size[t][k] += w->m.packets_of_size[t][k];
                lanes_packet_stats_add(&metrics->stats[t], &w->m.stats[t]);
            }
        }
        worker_free(w);
    }
    free(workers);
    if (metrics && job.subtree && (opt->queue == LANES_QUEUE_MAX || opt->queue == LANES_QUEUE_CORNER)) {
        /* queue nodes: the nodes holding queue_min triangles with no child that does */
        for (size_t i = 0; i < accel->bvh2.node_count; i++) {
            const lanes_bvh2_node *nd = &accel->bvh2.nodes[i];
            bool big = job.subtree[i] >= (uint32_t)opt->queue_min;
            bool big_child = nd->count == 0 && (job.subtree[nd->first] >= (uint32_t)opt->queue_min ||
                                                job.subtree[nd->first + 1] >= (uint32_t)opt->queue_min);
            metrics->queue_nodes += big && !big_child;
        }
    }
    free(job.quad_order);
    free(job.subtree);
    if (!ok) {
        free(job.rgb);
        return lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY, "render: out of memory");
    }
    float inv = 1.0f / (float)opt->base.spp;
    for (size_t i = 0; i < (size_t)job.width * (size_t)job.height * 3; i++) job.rgb[i] *= inv;
    out->rgb = job.rgb;
    out->width = job.width;
    out->height = job.height;
    out->rays = out->camera_rays + out->shadow_rays + out->secondary_rays;
    return LANES_OK;
}
