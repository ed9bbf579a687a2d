/* The public API (include/lanes/lanes.h): devices, accels and queries on top
 * of the kernel tables, the BVH builder and the wide-BVH collapse.
 *
 * Compiled for the x86-64 baseline; everything per ray happens in the
 * kernels of the device's set. Only the functions declared LANES_API are
 * exported from the shared library. */
#include "lanes/lanes.h"

#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "build/bvh.h"
#include "build/memory_limit.h"
#include "build/scene.h"
#include "simd/isa.h"
#include "build/accuracy.h"
#include "trace/kernels.h"

#define LANES_VERSION_TEXT_(a, b, c) #a "." #b "." #c
#define LANES_VERSION_TEXT(a, b, c) LANES_VERSION_TEXT_(a, b, c)

struct lanes_device_impl {
    const lanes_kernels *k;
    int threads;
    lanes_accuracy accuracy;
    lanes_error_callback callback;
    void *callback_user;
    atomic_int refs; /* the application's reference and one per accel */
};

struct lanes_accel_impl {
    lanes_device device;
    lanes_wbvh wide;
    size_t triangles, skipped;
    float bounds_min[3], bounds_max[3];
    /* The longest distance from a ray's origin across the scene that the
     * device's accuracy mode traces (lanes_accuracy_max_reach). */
    double max_reach;
};

LANES_API const char *lanes_version(void)
{
    return LANES_VERSION_TEXT(LANES_VERSION_MAJOR, LANES_VERSION_MINOR, LANES_VERSION_PATCH);
}

LANES_API const char *lanes_status_name(lanes_status status)
{
    switch (status) {
    case LANES_OK: return "ok";
    case LANES_ERR_UNKNOWN_ISA: return "unknown instruction set";
    case LANES_ERR_NOT_COMPILED: return "instruction set not compiled";
    case LANES_ERR_CPU_LACKS: return "the CPU cannot run the instruction set";
    case LANES_ERR_BAD_INPUT: return "bad input";
    case LANES_ERR_OUT_OF_MEMORY: return "out of memory";
    }
    return "unknown status";
}

/* Records the failure for this thread and tells the device's callback. */
static lanes_status fail(lanes_device device, lanes_status status, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
static lanes_status fail(lanes_device device, lanes_status status, const char *fmt, ...)
{
    char text[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    lanes_record_error(text);
    if (device && device->callback) device->callback(device->callback_user, status, text);
    return status;
}

/* ---------------------------------------------------------------- device */

/* One key=value of the config string; value is not NUL-terminated. */
static lanes_status apply_setting(struct lanes_device_impl *d, const char *key, size_t key_len,
                                  const char *value, size_t value_len, bool *isa_given, int *node_width)
{
    char v[64];
    if (value_len >= sizeof v)
        return fail(NULL, LANES_ERR_BAD_INPUT, "device config: the value of '%.*s' is too long",
                    (int)key_len, key);
    memcpy(v, value, value_len);
    v[value_len] = '\0';

    if (key_len == 3 && strncmp(key, "isa", 3) == 0) {
        lanes_isa isa = lanes_isa_from_name(v);
        char why[256];
        lanes_status st = lanes_isa_check(isa, why, sizeof why);
        if (st != LANES_OK)
            return fail(NULL, st, "device config: isa=%s: %s", v, why);
        d->k = lanes_kernels_for(isa);
        *isa_given = true;
    } else if (key_len == 7 && strncmp(key, "threads", 7) == 0) {
        char *end;
        long n = strtol(v, &end, 10);
        if (!v[0] || *end || n < 0 || n > 1024)
            return fail(NULL, LANES_ERR_BAD_INPUT,
                        "device config: threads=%s: not a whole number from 0 to 1024", v);
        d->threads = (int)n;
    } else if (key_len == 10 && strncmp(key, "node_width", 10) == 0) {
        if (strcmp(v, "4") && strcmp(v, "8") && strcmp(v, "16"))
            return fail(NULL, LANES_ERR_BAD_INPUT, "device config: node_width=%s: not 4, 8 or 16", v);
        *node_width = atoi(v);
    } else if (key_len == 8 && strncmp(key, "accuracy", 8) == 0) {
        int a = lanes_accuracy_from_name(v);
        if (a < 0)
            return fail(NULL, LANES_ERR_BAD_INPUT,
                        "device config: accuracy=%s: unknown mode (fast, default, robust)", v);
        d->accuracy = (lanes_accuracy)a;
    } else {
        return fail(NULL, LANES_ERR_BAD_INPUT,
                    "device config: unknown key '%.*s' (keys: isa, node_width, threads, accuracy)",
                    (int)key_len, key);
    }
    return LANES_OK;
}

static lanes_status parse_config(struct lanes_device_impl *d, const char *config, bool *isa_given,
                                 int *node_width)
{
    const char *p = config;
    while (p && *p) {
        p += strspn(p, " ,");
        if (!*p) break;
        size_t len = strcspn(p, ",");
        const char *eq = memchr(p, '=', len);
        size_t key_len = eq ? (size_t)(eq - p) : len;
        while (key_len > 0 && p[key_len - 1] == ' ') key_len--;
        if (!eq || key_len == 0)
            return fail(NULL, LANES_ERR_BAD_INPUT,
                        "device config: '%.*s' is not key=value (for example isa=avx2)", (int)len,
                        p);
        const char *value = eq + 1;
        size_t value_len = len - (size_t)(value - p);
        while (value_len > 0 && *value == ' ') value++, value_len--;
        while (value_len > 0 && value[value_len - 1] == ' ') value_len--;
        lanes_status st = apply_setting(d, p, key_len, value, value_len, isa_given, node_width);
        if (st != LANES_OK) return st;
        p += len;
    }
    return LANES_OK;
}

LANES_API lanes_status lanes_device_create(const char *config, lanes_device *device)
{
    if (!device) return fail(NULL, LANES_ERR_BAD_INPUT, "lanes_device_create: device is NULL");
    *device = NULL;
    struct lanes_device_impl *d = calloc(1, sizeof *d);
    if (!d) return fail(NULL, LANES_ERR_OUT_OF_MEMORY, "lanes_device_create: out of memory");
    d->accuracy = LANES_ACCURACY_DEFAULT;
    bool isa_given = false;
    int node_width = 0;
    lanes_status st = parse_config(d, config, &isa_given, &node_width);
    if (st == LANES_OK) {
        /* LANES_ISA and LANES_MAX_ISA, as for every program using lanes: a
         * bad value is an error here, not a quiet fall back to the best set,
         * unless isa= replaces it. Nothing replaces a bad
         * LANES_DISABLE_CPU_FEATURES. */
        char why[384];
        lanes_status env = lanes_isa_init(why, sizeof why);
        if (env != LANES_OK && (!isa_given || env == LANES_ERR_BAD_INPUT))
            st = fail(NULL, env, "%s", why);
        else if (!isa_given)
            d->k = lanes_kernels_for(lanes_isa_current());
    }
    if (st == LANES_OK && !d->k)
        st = fail(NULL, LANES_ERR_NOT_COMPILED, "lanes_device_create: no kernel set available");
    if (st == LANES_OK && node_width) {
        const lanes_kernels *k = lanes_kernels_for_width(d->k->isa, node_width);
        if (!k)
            st = fail(NULL, LANES_ERR_BAD_INPUT,
                      "device config: node_width=%d: the %s set (%d lanes) traverses nodes of %d children "
                      "or more, in whole vectors",
                      node_width, d->k->name, d->k->lanes, d->k->wide_width);
        else
            d->k = k;
    }
    if (st != LANES_OK) {
        free(d);
        return st;
    }
    atomic_init(&d->refs, 1);
    *device = d;
    return LANES_OK;
}

static void device_unref(lanes_device d)
{
    if (atomic_fetch_sub(&d->refs, 1) == 1) free(d);
}

LANES_API lanes_status lanes_device_release(lanes_device device)
{
    if (device) device_unref(device);
    return LANES_OK;
}

LANES_API lanes_status lanes_device_set_error_callback(lanes_device device,
                                                       lanes_error_callback callback, void *user)
{
    if (!device)
        return fail(NULL, LANES_ERR_BAD_INPUT, "lanes_device_set_error_callback: device is NULL");
    device->callback = callback;
    device->callback_user = user;
    return LANES_OK;
}

LANES_API lanes_status lanes_device_get_info(lanes_device device, lanes_device_info *info)
{
    if (!device || !info)
        return fail(device, LANES_ERR_BAD_INPUT, "lanes_device_get_info: %s is NULL",
                    device ? "info" : "device");
    info->isa = device->k->name;
    info->lanes = device->k->lanes;
    info->node_width = device->k->wide_width;
    info->accuracy = lanes_accuracy_name(device->accuracy);
    info->threads = device->threads;
    return LANES_OK;
}

/* ----------------------------------------------------------------- accel */

/* lanes_accel_create and lanes_accel_create_shared (named fn): the same
 * build; a shared accel then drops its copies of the triangles and keeps
 * the caller's arrays. */
static lanes_status accel_create(const char *fn, lanes_device device, const float *vertices,
                                 size_t vertex_count, const uint32_t *indices, size_t triangle_count,
                                 bool shared, lanes_accel *accel)
{
    if (!accel) return fail(device, LANES_ERR_BAD_INPUT, "%s: accel is NULL", fn);
    *accel = NULL;
    if (!device) return fail(NULL, LANES_ERR_BAD_INPUT, "%s: device is NULL", fn);
    if (!vertices || !indices)
        return fail(device, LANES_ERR_BAD_INPUT, "%s: %s is NULL", fn,
                    vertices ? "indices" : "vertices");
    if (triangle_count == 0) return fail(device, LANES_ERR_BAD_INPUT, "%s: no triangles", fn);
    if (triangle_count > (size_t)INT32_MAX)
        return fail(device, LANES_ERR_BAD_INPUT, "%s: %zu triangles; at most %d", fn,
                    triangle_count, INT32_MAX);
    if (shared && (triangle_count > LANES_WBVH_SHARED_MAX || vertex_count > LANES_WBVH_SHARED_MAX))
        return fail(device, LANES_ERR_BAD_INPUT,
                    "%s: %zu triangles and %zu vertices; a shared accel gathers with 32-bit offsets, "
                    "so at most %zu of each (lanes_accel_create copies and holds more)",
                    fn, triangle_count, vertex_count, LANES_WBVH_SHARED_MAX);
    for (size_t i = 0; i < 3 * triangle_count; i++)
        if (indices[i] >= vertex_count)
            return fail(device, LANES_ERR_BAD_INPUT,
                        "%s: triangle %zu: vertex index %u, but there are %zu vertices", fn, i / 3,
                        indices[i], vertex_count);

    lanes_error err = {0};
    double bytes = (double)triangle_count *
                   (double)(LANES_SCENE_BYTES_PER_TRIANGLE + LANES_ACCEL_BYTES_PER_TRIANGLE);
    if (lanes_memory_fits("an accel", bytes, &err) != LANES_OK)
        return fail(device, err.status, "%s: %s", fn, err.message);

    struct lanes_accel_impl *a = calloc(1, sizeof *a);
    lanes_scene scene;
    lanes_scene_init(&scene);
    scene.verts = malloc(triangle_count * 9 * sizeof(float));
    if (!a || !scene.verts) {
        free(a);
        free(scene.verts);
        return fail(device, LANES_ERR_OUT_OF_MEMORY, "%s: out of memory for %zu triangles", fn,
                    triangle_count);
    }
    size_t finite = 0;
    double edge2 = 0.0;
    for (size_t t = 0; t < triangle_count; t++) {
        float *v = scene.verts + 9 * t;
        for (int c = 0; c < 3; c++)
            memcpy(v + 3 * c, vertices + 3 * (size_t)indices[3 * t + c], 3 * sizeof(float));
        bool ok = true;
        for (int k = 0; k < 9; k++) ok = ok && isfinite(v[k]);
        finite += ok;
        for (int k = 0; ok && k < 3; k++) {
            const float *p = v + 3 * k, *q = v + 3 * ((k + 1) % 3);
            double dx = (double)q[0] - p[0], dy = (double)q[1] - p[1], dz = (double)q[2] - p[2];
            edge2 = fmax(edge2, dx * dx + dy * dy + dz * dz);
        }
    }
    scene.triangle_count = triangle_count;
    if (finite == 0) {
        free(a);
        free(scene.verts);
        return fail(device, LANES_ERR_BAD_INPUT, "%s: no triangle has finite coordinates", fn);
    }
    lanes_scene_bounds(&scene, a->bounds_min, a->bounds_max);
    double diag2 = 0.0;
    for (int k = 0; k < 3; k++) {
        double e = (double)a->bounds_max[k] - a->bounds_min[k];
        diag2 += e * e;
    }
    const lanes_accuracy mode = device->accuracy;
    const double max_reach = lanes_accuracy_max_reach(mode, sqrt(edge2));
    const double diagonal = sqrt(diag2), min_diagonal = lanes_accuracy_min_diagonal(mode);
    if (diagonal < min_diagonal || diagonal > max_reach) {
        free(a);
        free(scene.verts);
        return fail(device, LANES_ERR_BAD_INPUT,
                    "%s: the mesh's bounding-box diagonal %.3g is %s the %.3g that %s mode's "
                    "triangle test holds in float%s",
                    fn, diagonal, diagonal < min_diagonal ? "below" : "beyond",
                    diagonal < min_diagonal ? min_diagonal : max_reach, lanes_accuracy_name(mode),
                    mode != LANES_ACCURACY_ROBUST &&
                            (diagonal < min_diagonal
                                 ? LANES_ROBUST_MIN_DIAGONAL < min_diagonal
                                 : lanes_accuracy_max_reach(LANES_ACCURACY_ROBUST, 0) > max_reach)
                        ? " (robust mode holds more: accuracy=robust)"
                        : "");
    }

    lanes_bvh_build_options bo;
    lanes_bvh_default_options(&bo);
    bo.threads = device->threads;
    /* The wide BVH answers every query: single rays, streams and packets. */
    lanes_status status = lanes_wbvh_build(&scene, device->k->wide_width, &bo, &a->wide, &err);
    free(scene.verts);
    if (status == LANES_OK && shared && (status = lanes_wbvh_share(&a->wide, vertices, indices, &err)) != LANES_OK)
        lanes_wbvh_free(&a->wide);
    if (status != LANES_OK) {
        free(a);
        return fail(device, status, "%s: %s", fn, err.message);
    }
    a->triangles = triangle_count;
    a->max_reach = max_reach;
    a->skipped = triangle_count - finite;
    a->device = device;
    atomic_fetch_add(&device->refs, 1);
    *accel = a;
    return LANES_OK;
}

LANES_API lanes_status lanes_accel_create(lanes_device device, const float *vertices,
                                          size_t vertex_count, const uint32_t *indices,
                                          size_t triangle_count, lanes_accel *accel)
{
    return accel_create("lanes_accel_create", device, vertices, vertex_count, indices, triangle_count, false,
                        accel);
}

LANES_API lanes_status lanes_accel_create_shared(lanes_device device, const float *vertices,
                                                 size_t vertex_count, const uint32_t *indices,
                                                 size_t triangle_count, lanes_accel *accel)
{
    return accel_create("lanes_accel_create_shared", device, vertices, vertex_count, indices, triangle_count,
                        true, accel);
}

LANES_API lanes_status lanes_accel_release(lanes_accel accel)
{
    if (!accel) return LANES_OK;
    lanes_wbvh_free(&accel->wide);
    lanes_device d = accel->device;
    free(accel);
    device_unref(d);
    return LANES_OK;
}

LANES_API lanes_status lanes_accel_get_info(lanes_accel accel, lanes_accel_info *info)
{
    if (!accel || !info)
        return fail(accel ? accel->device : NULL, LANES_ERR_BAD_INPUT,
                    "lanes_accel_get_info: %s is NULL", accel ? "info" : "accel");
    info->isa = accel->device->k->name;
    info->accuracy = lanes_accuracy_name(accel->device->accuracy);
    info->triangles = accel->triangles;
    info->skipped = accel->skipped;
    info->nodes = accel->wide.node_count;
    info->node_width = accel->wide.width;
    info->bytes = lanes_wbvh_bytes(&accel->wide);
    memcpy(info->bounds_min, accel->bounds_min, sizeof info->bounds_min);
    memcpy(info->bounds_max, accel->bounds_max, sizeof info->bounds_max);
    info->build_seconds = accel->wide.build_seconds;
    info->max_reach = accel->max_reach;
    return LANES_OK;
}

/* --------------------------------------------------------------- queries */

/* Rays the kernels cannot answer right are traced as inactive ones
 * (misses): invalid ones, and those starting so far from the mesh that the
 * triangle test would overflow. The first of each kind is named. */
typedef struct refused_rays {
    size_t invalid, first_invalid;
    size_t far, first_far;
    double first_far_reach;
} refused_rays;

static lanes_status query_result(lanes_accel accel, const char *fn, const refused_rays *bad)
{
    if (bad->invalid)
        return fail(accel->device, LANES_ERR_BAD_INPUT,
                    "%s: %zu invalid ray%s (NaN or infinite origin or direction, zero direction, "
                    "or NaN tnear/tfar), the first is ray %zu%s; they were reported as misses",
                    fn, bad->invalid, bad->invalid == 1 ? "" : "s", bad->first_invalid,
                    bad->far ? ", and rays starting too far from the mesh" : "");
    if (bad->far)
        return fail(accel->device, LANES_ERR_BAD_INPUT,
                    "%s: %zu ray%s start%s too far from the mesh for %s mode: ray %zu reaches "
                    "%.3g across it, beyond the %.3g its triangle test holds in float (float "
                    "overflows)%s; they were reported as misses",
                    fn, bad->far, bad->far == 1 ? "" : "s", bad->far == 1 ? "s" : "",
                    lanes_accuracy_name(accel->device->accuracy), bad->first_far,
                    bad->first_far_reach, accel->max_reach,
                    lanes_accuracy_max_reach(LANES_ACCURACY_ROBUST, 0) > accel->max_reach
                        ? " (robust mode reaches further: accuracy=robust)"
                        : "");
    return LANES_OK;
}

/* The squared diagonal of the box of the mesh and the ray's origin, in
 * double: the longest distance the ray's triangle tests meet, squared. */
static double ray_reach2(lanes_accel accel, const lanes_ray *ray)
{
    double d2 = 0.0;
    for (int k = 0; k < 3; k++) {
        double o = ray->o[k];
        double e = fmax(accel->bounds_max[k], o) - fmin(accel->bounds_min[k], o);
        d2 += e * e;
    }
    return d2;
}

/* Ray i of a SoA stream in the kernels' form, prepared for the device's
 * accuracy mode, or made inactive when it is refused. */
static lanes_ray load_ray(lanes_accel accel, const lanes_rays_soa *r, size_t i, lanes_rcp_mode rcp,
                          refused_rays *bad, size_t index)
{
    lanes_ray ray = {{r->org_x[i], r->org_y[i], r->org_z[i]},
                     {r->dir_x[i], r->dir_y[i], r->dir_z[i]},
                     {0, 0, 0},
                     r->tnear[i],
                     r->tfar[i]};
    if (!lanes_ray_prepare_rcp(&ray, rcp)) {
        if (bad->invalid++ == 0) bad->first_invalid = index;
        return ray;
    }
    double reach2 = ray_reach2(accel, &ray);
    if (reach2 > accel->max_reach * accel->max_reach) {
        if (bad->far++ == 0) bad->first_far = index, bad->first_far_reach = sqrt(reach2);
        ray.tnear = INFINITY;
        ray.tfar = -INFINITY;
    }
    return ray;
}

static void store_hit(lanes_hits_soa *h, size_t i, const lanes_hit *hit)
{
    bool found = hit->prim != LANES_NO_HIT;
    h->t[i] = found ? hit->t : INFINITY;
    if (h->u) h->u[i] = found ? hit->u : 0.0f;
    if (h->v) h->v[i] = found ? hit->v : 0.0f;
    h->prim_id[i] = found ? hit->prim : LANES_INVALID_ID;
}

static bool soa_complete(const lanes_rays_soa *r)
{
    return r->org_x && r->org_y && r->org_z && r->dir_x && r->dir_y && r->dir_z && r->tnear &&
           r->tfar;
}

/* The checks every query of n rays makes; LANES_OK when it may go on.
 * Zero rays need no arrays. */
static lanes_status check_query(lanes_accel accel, const char *fn, size_t n, const void *rays,
                                bool rays_complete, const void *out, bool out_complete)
{
    if (!accel) return fail(NULL, LANES_ERR_BAD_INPUT, "%s: accel is NULL", fn);
    if (n == 0) return LANES_OK;
    if (!rays || !rays_complete)
        return fail(accel->device, LANES_ERR_BAD_INPUT, "%s: the ray%s NULL", fn,
                    rays ? "s have an array that is" : " is");
    if (!out || !out_complete)
        return fail(accel->device, LANES_ERR_BAD_INPUT, "%s: the result%s NULL", fn,
                    out ? " has an array that is" : " is");
    return LANES_OK;
}

static lanes_rays_soa single_as_soa(const lanes_ray1 *r)
{
    lanes_rays_soa s = {&r->org[0], &r->org[1], &r->org[2], &r->dir[0],
                        &r->dir[1], &r->dir[2], &r->tnear, &r->tfar};
    return s;
}

/* Renderers call the single-ray queries once per ray, so they go straight
 * to the kernel rather than through the stream's chunk loop. */
LANES_API lanes_status lanes_intersect1(lanes_accel accel, const lanes_ray1 *ray, lanes_hit1 *hit)
{
    static const char fn[] = "lanes_intersect1";
    lanes_status st = check_query(accel, fn, 1, ray, true, hit, true);
    if (st != LANES_OK) return st;
    const lanes_device d = accel->device;
    lanes_rays_soa one = single_as_soa(ray);
    refused_rays bad = {0};
    lanes_ray r = load_ray(accel, &one, 0, lanes_accuracy_precision(d->accuracy).rcp, &bad, 0);
    lanes_hit found;
    d->k->trace_wide(&accel->wide, d->accuracy, &r, 1, &found, NULL);
    lanes_hits_soa out = {&hit->t, &hit->u, &hit->v, &hit->prim_id};
    store_hit(&out, 0, &found);
    return query_result(accel, fn, &bad);
}

LANES_API lanes_status lanes_occluded1(lanes_accel accel, const lanes_ray1 *ray, bool *occluded)
{
    static const char fn[] = "lanes_occluded1";
    lanes_status st = check_query(accel, fn, 1, ray, true, occluded, true);
    if (st != LANES_OK) return st;
    const lanes_device d = accel->device;
    lanes_rays_soa one = single_as_soa(ray);
    refused_rays bad = {0};
    lanes_ray r = load_ray(accel, &one, 0, lanes_accuracy_precision(d->accuracy).rcp, &bad, 0);
    uint8_t hit = 0;
    d->k->occluded_wide(&accel->wide, d->accuracy, &r, 1, &hit, NULL);
    *occluded = hit != 0;
    return query_result(accel, fn, &bad);
}

/* A multiple of every set's lane count, so that chunks cut no packet, and
 * enough rays that incoherent shadow rays fill the occlusion stream's
 * octant groups of 32. */
#define STREAM_CHUNK 256

/* Rays through the wide BVH in chunks (the traversal takes an array):
 * closest hits into hits, or, with occluded, any hits. Closest hits one at
 * a time, any hits as an octant-sorted stream (the same answers); or, with
 * packets, as hybrid packets of the set's lane count. */
static lanes_status trace_rays(lanes_accel accel, const char *fn, const lanes_rays_soa *rays,
                               size_t n, lanes_hits_soa *hits, uint8_t *occluded, bool packets)
{
    const lanes_device d = accel->device;
    const lanes_rcp_mode rcp = lanes_accuracy_precision(d->accuracy).rcp;
    refused_rays bad = {0};
    lanes_ray chunk[STREAM_CHUNK];
    lanes_hit found[STREAM_CHUNK];
    uint8_t flags[STREAM_CHUNK];
    const float box[6] = {accel->bounds_min[0], accel->bounds_min[1], accel->bounds_min[2],
                          accel->bounds_max[0], accel->bounds_max[1], accel->bounds_max[2]};
    const float far2 = (float)fmin(accel->max_reach * accel->max_reach, FLT_MAX);
    for (size_t first = 0; first < n; first += STREAM_CHUNK) {
        size_t m = n - first < STREAM_CHUNK ? n - first : STREAM_CHUNK;
        /* the set's SIMD set-up in exact mode; the flagged rays, and every
         * ray in fast mode (whose estimate the scalar path shares with
         * lanes_intersect1), one at a time */
        bool all = rcp != LANES_RCP_EXACT;
        const float *const soa[8] = {rays->org_x + first, rays->org_y + first, rays->org_z + first,
                                     rays->dir_x + first, rays->dir_y + first, rays->dir_z + first,
                                     rays->tnear + first, rays->tfar + first};
        if (all || d->k->rays_load_soa(soa, m, box, far2, chunk, flags) > 0)
            for (size_t i = 0; i < m; i++)
                if (all || flags[i]) chunk[i] = load_ray(accel, rays, first + i, rcp, &bad, first + i);
        if (occluded) {
            memset(occluded + first, 0, m);
            (packets ? d->k->occluded_hybrid : d->k->occluded_stream)(&accel->wide, d->accuracy, chunk, m,
                                                                      occluded + first, NULL);
        } else {
            (packets ? d->k->trace_hybrid : d->k->trace_wide)(&accel->wide, d->accuracy, chunk, m, found, NULL);
            for (size_t i = 0; i < m; i++) store_hit(hits, first + i, &found[i]);
        }
    }
    return query_result(accel, fn, &bad);
}

LANES_API lanes_status lanes_intersect_stream(lanes_accel accel, const lanes_rays_soa *rays,
                                              size_t n, lanes_hits_soa *hits)
{
    static const char fn[] = "lanes_intersect_stream";
    lanes_status st = check_query(accel, fn, n, rays, rays && soa_complete(rays), hits,
                                  hits && hits->t && hits->prim_id);
    return st != LANES_OK ? st : trace_rays(accel, fn, rays, n, hits, NULL, false);
}

LANES_API lanes_status lanes_occluded_stream(lanes_accel accel, const lanes_rays_soa *rays,
                                             size_t n, uint8_t *occluded)
{
    static const char fn[] = "lanes_occluded_stream";
    lanes_status st = check_query(accel, fn, n, rays, rays && soa_complete(rays), occluded, true);
    return st != LANES_OK ? st : trace_rays(accel, fn, rays, n, NULL, occluded, false);
}

LANES_API lanes_status lanes_intersect_packet(lanes_accel accel, const lanes_rays_soa *rays,
                                              size_t n, lanes_hits_soa *hits)
{
    static const char fn[] = "lanes_intersect_packet";
    lanes_status st = check_query(accel, fn, n, rays, rays && soa_complete(rays), hits,
                                  hits && hits->t && hits->prim_id);
    return st != LANES_OK ? st : trace_rays(accel, fn, rays, n, hits, NULL, true);
}

LANES_API lanes_status lanes_occluded_packet(lanes_accel accel, const lanes_rays_soa *rays,
                                             size_t n, uint8_t *occluded)
{
    static const char fn[] = "lanes_occluded_packet";
    lanes_status st = check_query(accel, fn, n, rays, rays && soa_complete(rays), occluded, true);
    return st != LANES_OK ? st : trace_rays(accel, fn, rays, n, NULL, occluded, true);
}
