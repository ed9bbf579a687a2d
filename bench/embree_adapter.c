/* Embree 3 behind the interface of embree_adapter.h. */
#define _POSIX_C_SOURCE 200809L /* clock_gettime */
#include "bench/embree_adapter.h"

#include <embree3/rtcore.h>
#include <math.h>
#include <pmmintrin.h> /* baseline SSE3 header, only for the MXCSR macros */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <xmmintrin.h>

#include "simd/isa.h"

static const char *const isa_names[LANES_EMBREE_ISA_COUNT] = {"sse2", "sse4.2", "avx", "avx2",
                                                              "avx512"};

/* What Embree's own check asks of the CPU for each set (its SSE42 includes
 * POPCNT, its AVX2 the BMI and FMA extensions, its AVX512 the SKX subset). */
static uint32_t isa_needs(lanes_embree_isa isa)
{
    const uint32_t sse2 = LANES_CPU_SSE2;
    const uint32_t sse42 = sse2 | LANES_CPU_SSE3 | LANES_CPU_SSSE3 | LANES_CPU_SSE41 |
                           LANES_CPU_SSE42 | LANES_CPU_POPCNT;
    const uint32_t avx = sse42 | LANES_CPU_AVX;
    const uint32_t avx2 = avx | LANES_CPU_AVX2 | LANES_CPU_FMA | LANES_CPU_BMI1 | LANES_CPU_BMI2 |
                          LANES_CPU_LZCNT | LANES_CPU_F16C;
    const uint32_t avx512 = avx2 | LANES_CPU_AVX512F | LANES_CPU_AVX512CD | LANES_CPU_AVX512DQ |
                            LANES_CPU_AVX512BW | LANES_CPU_AVX512VL;
    switch (isa) {
    case LANES_EMBREE_SSE2: return sse2;
    case LANES_EMBREE_SSE42: return sse42;
    case LANES_EMBREE_AVX: return avx;
    case LANES_EMBREE_AVX2: return avx2;
    case LANES_EMBREE_AVX512: return avx512;
    default: return ~0u;
    }
}

const char *lanes_embree_isa_name(lanes_embree_isa isa)
{
    return isa >= 0 && isa < LANES_EMBREE_ISA_COUNT ? isa_names[isa] : "?";
}

lanes_embree_isa lanes_embree_isa_from_name(const char *name)
{
    for (int i = 0; name && i < LANES_EMBREE_ISA_COUNT; i++)
        if (strcmp(name, isa_names[i]) == 0) return (lanes_embree_isa)i;
    return LANES_EMBREE_ISA_NONE;
}

bool lanes_embree_isa_cpu_can_run(lanes_embree_isa isa)
{
    uint32_t need = isa_needs(isa);
    return (lanes_cpu()->bits & need) == need;
}

lanes_embree_isa lanes_embree_isa_best(void)
{
    for (int i = LANES_EMBREE_ISA_COUNT - 1; i >= 0; i--)
        if (lanes_embree_isa_cpu_can_run((lanes_embree_isa)i)) return (lanes_embree_isa)i;
    return LANES_EMBREE_SSE2;
}

const char *lanes_embree_isa_all_names(void) { return "sse2, sse4.2, avx, avx2, avx512"; }

const char *lanes_embree_method_name(lanes_embree_method m, bool occlusion)
{
    static const char *const isect[] = {"rtcIntersect1",  "rtcIntersect4",  "rtcIntersect8",
                                        "rtcIntersect16", "rtcIntersect1M", "rtcIntersectNp"};
    static const char *const occl[] = {"rtcOccluded1",  "rtcOccluded4",  "rtcOccluded8",
                                       "rtcOccluded16", "rtcOccluded1M", "rtcOccludedNp"};
    if (m < 0 || m >= LANES_EMBREE_METHOD_COUNT) return "?";
    return occlusion ? occl[m] : isect[m];
}

int lanes_embree_method_width(lanes_embree_method m)
{
    switch (m) {
    case LANES_EMBREE_4: return 4;
    case LANES_EMBREE_8: return 8;
    case LANES_EMBREE_16: return 16;
    default: return 1;
    }
}

unsigned lanes_fp_fast_enter(void)
{
    unsigned saved = _mm_getcsr();
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
    return saved;
}

void lanes_fp_restore(unsigned saved) { _mm_setcsr(saved); }

struct lanes_embree {
    RTCDevice device;
    RTCScene scene;
    lanes_embree_isa isa;
    double build_seconds;
    long long bytes_now;    /* Embree's own count, through its memory monitor */
    long long bvh_bytes;    /* what rtcCommitScene added: the BVH and its leaves */
    bool native[LANES_EMBREE_METHOD_COUNT];
    char error[256];
};

static void on_error(void *user, enum RTCError code, const char *str)
{
    lanes_embree *e = user;
    if (e->error[0] == '\0')
        snprintf(e->error, sizeof e->error, "Embree error %d: %s", (int)code, str ? str : "");
}

/* Embree reports every allocation and release; the build's net is the
 * memory its BVH keeps. */
static bool on_memory(void *user, ssize_t bytes, bool post)
{
    (void)post;
    lanes_embree *e = user;
    e->bytes_now += (long long)bytes;
    return true;
}

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

lanes_status lanes_embree_create(const lanes_scene *scene, lanes_embree_isa isa, int threads,
                                 lanes_embree **out, lanes_error *err)
{
    lanes_status status = LANES_OK;
    *out = NULL;
    if (isa < 0 || isa >= LANES_EMBREE_ISA_COUNT) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "embree: unknown ISA (valid: %s)",
                               lanes_embree_isa_all_names());
    }
    if (!lanes_embree_isa_cpu_can_run(isa)) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "embree: this CPU cannot run Embree's %s kernels",
                               lanes_embree_isa_name(isa));
    }
    if (scene->triangle_count == 0 || scene->triangle_count > UINT32_MAX / 3) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "embree: %zu triangles (need 1 .. %u)",
                               scene->triangle_count, UINT32_MAX / 3);
    }
    lanes_embree *e = calloc(1, sizeof *e);
    if (!e) {
        return lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY, "embree: out of memory");
    }
    e->isa = isa;
    char config[96];
    snprintf(config, sizeof config, "isa=%s,threads=%d", isa_names[isa], threads < 0 ? 0 : threads);
    e->device = rtcNewDevice(config);
    if (!e->device) {
        status = lanes_error_set(err, LANES_ERR_BAD_INPUT, "embree: rtcNewDevice(\"%s\") failed (error %d)",
                                 config, (int)rtcGetDeviceError(NULL));
        free(e);
        return status;
    }
    rtcSetDeviceErrorFunction(e->device, on_error, e);
    rtcSetDeviceMemoryMonitorFunction(e->device, on_memory, e);
    e->native[LANES_EMBREE_1] = true;
    e->native[LANES_EMBREE_4] = rtcGetDeviceProperty(e->device, RTC_DEVICE_PROPERTY_NATIVE_RAY4_SUPPORTED) != 0;
    e->native[LANES_EMBREE_8] = rtcGetDeviceProperty(e->device, RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED) != 0;
    e->native[LANES_EMBREE_16] = rtcGetDeviceProperty(e->device, RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED) != 0;
    e->native[LANES_EMBREE_1M] = rtcGetDeviceProperty(e->device, RTC_DEVICE_PROPERTY_RAY_STREAM_SUPPORTED) != 0;
    e->native[LANES_EMBREE_NP] = e->native[LANES_EMBREE_1M];

    /* Three vertices per triangle, as the scene stores them: no welding, so
     * primID i is scene triangle i and each triangle's vertices are bitwise
     * those lanes reads. Embree's own buffers come padded for its 16-byte
     * vertex loads. */
    size_t n = scene->triangle_count;
    RTCGeometry g = rtcNewGeometry(e->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    float *v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                       3 * sizeof(float), 3 * n);
    unsigned *idx = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                            3 * sizeof(unsigned), n);
    if (!v || !idx) {
        status = lanes_error_set(err, LANES_ERR_BAD_INPUT,
                                 "embree: cannot allocate buffers for %zu triangles: %s", n, e->error);
        rtcReleaseGeometry(g);
        lanes_embree_destroy(e);
        return status;
    }
    memcpy(v, scene->verts, n * 9 * sizeof(float));
    for (size_t i = 0; i < 3 * n; i++) idx[i] = (unsigned)i;
    rtcCommitGeometry(g);
    e->scene = rtcNewScene(e->device);
    rtcAttachGeometryByID(e->scene, g, 0);
    rtcReleaseGeometry(g);

    unsigned csr = lanes_fp_fast_enter();
    long long before = e->bytes_now;
    double t0 = now_seconds();
    rtcCommitScene(e->scene);
    e->build_seconds = now_seconds() - t0;
    e->bvh_bytes = e->bytes_now - before;
    lanes_fp_restore(csr);
    if (e->error[0]) {
        status = lanes_error_set(err, LANES_ERR_BAD_INPUT, "embree: building the scene: %s", e->error);
        lanes_embree_destroy(e);
        return status;
    }
    *out = e;
    return LANES_OK;
}

void lanes_embree_destroy(lanes_embree *e)
{
    if (!e) return;
    if (e->scene) rtcReleaseScene(e->scene);
    if (e->device) rtcReleaseDevice(e->device);
    free(e);
}

double lanes_embree_build_seconds(const lanes_embree *e) { return e->build_seconds; }
double lanes_embree_bvh_bytes(const lanes_embree *e) { return (double)e->bvh_bytes; }
lanes_embree_isa lanes_embree_get_isa(const lanes_embree *e) { return e->isa; }
const char *lanes_embree_error(const lanes_embree *e) { return e->error; }

bool lanes_embree_supports(const lanes_embree *e, lanes_embree_method m)
{
    return m >= 0 && m < LANES_EMBREE_METHOD_COUNT && e->native[m];
}

/* ---- batches ---------------------------------------------------------- */

/* The Np layout: one array per field, in RTCRayNp's order, then
 * RTCHitNp's (Ng_x, Ng_y, Ng_z, u, v, primID, geomID, instID[0]). */
enum { NP_ORG_X, NP_ORG_Y, NP_ORG_Z, NP_TNEAR, NP_DIR_X, NP_DIR_Y, NP_DIR_Z, NP_TIME, NP_TFAR, NP_MASK, NP_ID, NP_FLAGS,
       NP_RAY_FIELDS, NP_NG_X = NP_RAY_FIELDS, NP_NG_Y, NP_NG_Z, NP_U, NP_V, NP_PRIM, NP_GEOM, NP_INST, NP_FIELDS };

static float *np_field(const lanes_embree_batch *b, int field) { return (float *)b->data + (size_t)field * b->count; }
static unsigned *np_ufield(const lanes_embree_batch *b, int field) { return (unsigned *)b->data + (size_t)field * b->count; }

/* Rays [begin, end) of an Np batch as Embree's pointer structs. */
static struct RTCRayNp np_rays(const lanes_embree_batch *b, size_t begin)
{
    return (struct RTCRayNp){np_field(b, NP_ORG_X) + begin, np_field(b, NP_ORG_Y) + begin, np_field(b, NP_ORG_Z) + begin,
                             np_field(b, NP_TNEAR) + begin, np_field(b, NP_DIR_X) + begin, np_field(b, NP_DIR_Y) + begin,
                             np_field(b, NP_DIR_Z) + begin, np_field(b, NP_TIME) + begin, np_field(b, NP_TFAR) + begin,
                             np_ufield(b, NP_MASK) + begin, np_ufield(b, NP_ID) + begin, np_ufield(b, NP_FLAGS) + begin};
}

static struct RTCHitNp np_hits(const lanes_embree_batch *b, size_t begin)
{
    return (struct RTCHitNp){np_field(b, NP_NG_X) + begin,  np_field(b, NP_NG_Y) + begin,   np_field(b, NP_NG_Z) + begin,
                             np_field(b, NP_U) + begin,     np_field(b, NP_V) + begin,      np_ufield(b, NP_PRIM) + begin,
                             np_ufield(b, NP_GEOM) + begin, {np_ufield(b, NP_INST) + begin}};
}

static void np_fill(lanes_embree_batch *b, const lanes_ray *rays)
{
    for (size_t i = 0; i < b->count; i++) {
        const lanes_ray *s = &rays[i];
        np_field(b, NP_ORG_X)[i] = s->o[0], np_field(b, NP_ORG_Y)[i] = s->o[1], np_field(b, NP_ORG_Z)[i] = s->o[2];
        np_field(b, NP_DIR_X)[i] = s->d[0], np_field(b, NP_DIR_Y)[i] = s->d[1], np_field(b, NP_DIR_Z)[i] = s->d[2];
        np_field(b, NP_TNEAR)[i] = s->tnear, np_field(b, NP_TFAR)[i] = s->tfar, np_field(b, NP_TIME)[i] = 0.0f;
        np_ufield(b, NP_MASK)[i] = ~0u, np_ufield(b, NP_ID)[i] = (unsigned)i, np_ufield(b, NP_FLAGS)[i] = 0;
        if (!b->occlusion)
            np_ufield(b, NP_PRIM)[i] = np_ufield(b, NP_GEOM)[i] = np_ufield(b, NP_INST)[i] = RTC_INVALID_GEOMETRY_ID;
    }
}

static size_t element_size(lanes_embree_method m, bool occlusion)
{
    switch (m) {
    case LANES_EMBREE_NP: return (occlusion ? NP_RAY_FIELDS : NP_FIELDS) * sizeof(float);
    case LANES_EMBREE_4: return occlusion ? sizeof(struct RTCRay4) : sizeof(struct RTCRayHit4);
    case LANES_EMBREE_8: return occlusion ? sizeof(struct RTCRay8) : sizeof(struct RTCRayHit8);
    case LANES_EMBREE_16: return occlusion ? sizeof(struct RTCRay16) : sizeof(struct RTCRayHit16);
    default: return occlusion ? sizeof(struct RTCRay) : sizeof(struct RTCRayHit);
    }
}

/* aligned_alloc wants a size that is a multiple of the alignment. */
static void *alloc_aligned(size_t bytes)
{
    size_t rounded = (bytes + 63) / 64 * 64;
    return rounded >= bytes ? aligned_alloc(64, rounded ? rounded : 64) : NULL;
}

/* The packet structs are all "float field[W]" in the same order, so one
 * writer serves the three widths through a lane stride. */
#define PACKET_FILL(RAYT, HITT, W)                                                         \
    do {                                                                                   \
        for (size_t k = 0; k < packets; k++) {                                             \
            struct RAYT *r;                                                                \
            struct HITT *h = NULL;                                                         \
            if (occlusion) {                                                               \
                r = (struct RAYT *)b->data + k;                                            \
            } else {                                                                       \
                r = (struct RAYT *)(void *)((char *)b->data + k * elem);                   \
                h = (struct HITT *)(void *)((char *)r + sizeof(struct RAYT));              \
            }                                                                              \
            for (int j = 0; j < (W); j++) {                                                \
                size_t i = k * (W) + (size_t)j;                                            \
                /* lanes past the count repeat a harmless ray the valid mask hides */      \
                const lanes_ray *s = &rays[i < n ? i : n - 1];                             \
                r->org_x[j] = s->o[0], r->org_y[j] = s->o[1], r->org_z[j] = s->o[2];       \
                r->dir_x[j] = s->d[0], r->dir_y[j] = s->d[1], r->dir_z[j] = s->d[2];       \
                r->tnear[j] = s->tnear, r->tfar[j] = s->tfar, r->time[j] = 0.0f;           \
                r->mask[j] = ~0u, r->id[j] = (unsigned)i, r->flags[j] = 0;                 \
                if (h) {                                                                   \
                    h->geomID[j] = RTC_INVALID_GEOMETRY_ID;                                \
                    h->primID[j] = RTC_INVALID_GEOMETRY_ID;                                \
                    h->instID[0][j] = RTC_INVALID_GEOMETRY_ID;                             \
                }                                                                          \
            }                                                                              \
        }                                                                                  \
    } while (0)

lanes_status lanes_embree_batch_init(lanes_embree_batch *b, lanes_embree_method m, bool occlusion,
                                     const lanes_ray *rays, size_t n, lanes_error *err)
{
    memset(b, 0, sizeof *b);
    b->method = m;
    b->occlusion = occlusion;
    b->count = n;
    size_t w = (size_t)lanes_embree_method_width(m);
    size_t elem = element_size(m, occlusion);
    size_t packets = (n + w - 1) / w;
    if (n == 0) packets = 0;
    if (packets > SIZE_MAX / 2 / elem) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "embree: %zu rays is too many", n);
    }
    b->bytes = packets * elem;
    b->data = alloc_aligned(b->bytes);
    b->pristine = alloc_aligned(b->bytes);
    b->valid_full = alloc_aligned(16 * sizeof(int));
    b->valid_tail = alloc_aligned(16 * sizeof(int));
    if (!b->data || !b->pristine || !b->valid_full || !b->valid_tail) {
        lanes_embree_batch_free(b);
        return lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY, "embree: out of memory for %zu rays", n);
    }
    size_t tail = n % w;
    for (size_t j = 0; j < 16; j++) {
        b->valid_full[j] = j < w ? -1 : 0;
        b->valid_tail[j] = (tail == 0 ? j < w : j < tail) ? -1 : 0;
    }
    if (n == 0) return LANES_OK;
    memset(b->data, 0, b->bytes); /* padding and unused hit fields: a deterministic pristine copy */

    switch (m) {
    case LANES_EMBREE_4: PACKET_FILL(RTCRay4, RTCHit4, 4); break;
    case LANES_EMBREE_8: PACKET_FILL(RTCRay8, RTCHit8, 8); break;
    case LANES_EMBREE_16: PACKET_FILL(RTCRay16, RTCHit16, 16); break;
    case LANES_EMBREE_NP: np_fill(b, rays); break;
    default:
        for (size_t i = 0; i < n; i++) {
            struct RTCRay *r = occlusion ? (struct RTCRay *)b->data + i
                                         : &((struct RTCRayHit *)b->data)[i].ray;
            const lanes_ray *s = &rays[i];
            r->org_x = s->o[0], r->org_y = s->o[1], r->org_z = s->o[2];
            r->dir_x = s->d[0], r->dir_y = s->d[1], r->dir_z = s->d[2];
            r->tnear = s->tnear, r->tfar = s->tfar, r->time = 0.0f;
            r->mask = ~0u, r->id = (unsigned)i, r->flags = 0;
            if (!occlusion) {
                struct RTCHit *h = &((struct RTCRayHit *)b->data)[i].hit;
                memset(h, 0, sizeof *h);
                h->geomID = h->primID = h->instID[0] = RTC_INVALID_GEOMETRY_ID;
            }
        }
        break;
    }
    memcpy(b->pristine, b->data, b->bytes);
    return LANES_OK;
}

void lanes_embree_batch_free(lanes_embree_batch *b)
{
    free(b->data);
    free(b->pristine);
    free(b->valid_full);
    free(b->valid_tail);
    memset(b, 0, sizeof *b);
}

void lanes_embree_batch_reset(lanes_embree_batch *b)
{
    if (b->bytes) memcpy(b->data, b->pristine, b->bytes);
}

void lanes_embree_batch_trace(const lanes_embree *e, lanes_embree_batch *b, size_t begin,
                              size_t end, bool coherent)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    if (coherent) ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    if (end > b->count) end = b->count;
    if (begin >= end) return;
    RTCScene s = e->scene;
    size_t w = (size_t)lanes_embree_method_width(b->method);
    size_t last = (b->count - 1) / w; /* the packet that may be partial */
    switch (b->method) {
    case LANES_EMBREE_1:
        if (b->occlusion) {
            struct RTCRay *r = b->data;
            for (size_t i = begin; i < end; i++) rtcOccluded1(s, &ctx, &r[i]);
        } else {
            struct RTCRayHit *r = b->data;
            for (size_t i = begin; i < end; i++) rtcIntersect1(s, &ctx, &r[i]);
        }
        break;
    case LANES_EMBREE_1M:
        if (b->occlusion)
            rtcOccluded1M(s, &ctx, (struct RTCRay *)b->data + begin, (unsigned)(end - begin),
                          sizeof(struct RTCRay));
        else
            rtcIntersect1M(s, &ctx, (struct RTCRayHit *)b->data + begin, (unsigned)(end - begin),
                           sizeof(struct RTCRayHit));
        break;
    case LANES_EMBREE_NP: {
        struct RTCRayNp r = np_rays(b, begin);
        if (b->occlusion) {
            rtcOccludedNp(s, &ctx, &r, (unsigned)(end - begin));
        } else {
            struct RTCRayHitNp rh = {r, np_hits(b, begin)};
            rtcIntersectNp(s, &ctx, &rh, (unsigned)(end - begin));
        }
        break;
    }
#define PACKET_LOOP(W)                                                                     \
    for (size_t k = begin / (W); k * (W) < end; k++) {                                     \
        const int *valid = k == last ? b->valid_tail : b->valid_full;                      \
        if (b->occlusion)                                                                  \
            rtcOccluded##W(valid, s, &ctx, (struct RTCRay##W *)b->data + k);               \
        else                                                                               \
            rtcIntersect##W(valid, s, &ctx, (struct RTCRayHit##W *)b->data + k);           \
    }
    case LANES_EMBREE_4: PACKET_LOOP(4) break;
    case LANES_EMBREE_8: PACKET_LOOP(8) break;
    case LANES_EMBREE_16: PACKET_LOOP(16) break;
#undef PACKET_LOOP
    default: break;
    }
}

static lanes_hit make_hit(unsigned geom, unsigned prim, float t, float u, float v)
{
    if (geom == RTC_INVALID_GEOMETRY_ID) return (lanes_hit){INFINITY, 0.0f, 0.0f, LANES_NO_HIT};
    return (lanes_hit){t, u, v, prim};
}

void lanes_embree_batch_hits(const lanes_embree_batch *b, lanes_hit *hits)
{
    if (b->occlusion) return;
    size_t n = b->count;
    switch (b->method) {
#define PACKET_HITS(W)                                                                     \
    for (size_t i = 0; i < n; i++) {                                                       \
        const struct RTCRayHit##W *p = (const struct RTCRayHit##W *)b->data + i / (W);     \
        size_t j = i % (W);                                                                \
        hits[i] = make_hit(p->hit.geomID[j], p->hit.primID[j], p->ray.tfar[j], p->hit.u[j], \
                           p->hit.v[j]);                                                   \
    }
    case LANES_EMBREE_4: PACKET_HITS(4) break;
    case LANES_EMBREE_8: PACKET_HITS(8) break;
    case LANES_EMBREE_16: PACKET_HITS(16) break;
#undef PACKET_HITS
    case LANES_EMBREE_NP:
        for (size_t i = 0; i < n; i++)
            hits[i] = make_hit(np_ufield(b, NP_GEOM)[i], np_ufield(b, NP_PRIM)[i], np_field(b, NP_TFAR)[i],
                               np_field(b, NP_U)[i], np_field(b, NP_V)[i]);
        break;
    default:
        for (size_t i = 0; i < n; i++) {
            const struct RTCRayHit *r = (const struct RTCRayHit *)b->data + i;
            hits[i] = make_hit(r->hit.geomID, r->hit.primID, r->ray.tfar, r->hit.u, r->hit.v);
        }
        break;
    }
}

/* Embree marks an occluded ray by tfar = -inf. */
void lanes_embree_batch_occluded(const lanes_embree_batch *b, uint8_t *occluded)
{
    if (!b->occlusion) return;
    size_t n = b->count;
    switch (b->method) {
#define PACKET_OCC(W)                                                                      \
    for (size_t i = 0; i < n; i++) {                                                       \
        const struct RTCRay##W *p = (const struct RTCRay##W *)b->data + i / (W);           \
        occluded[i] = p->tfar[i % (W)] == -INFINITY;                                       \
    }
    case LANES_EMBREE_4: PACKET_OCC(4) break;
    case LANES_EMBREE_8: PACKET_OCC(8) break;
    case LANES_EMBREE_16: PACKET_OCC(16) break;
#undef PACKET_OCC
    case LANES_EMBREE_NP:
        for (size_t i = 0; i < n; i++) occluded[i] = np_field(b, NP_TFAR)[i] == -INFINITY;
        break;
    default:
        for (size_t i = 0; i < n; i++) occluded[i] = ((const struct RTCRay *)b->data)[i].tfar == -INFINITY;
        break;
    }
}

static void fill_ray(struct RTCRay *r, const lanes_ray *s)
{
    r->org_x = s->o[0], r->org_y = s->o[1], r->org_z = s->o[2];
    r->dir_x = s->d[0], r->dir_y = s->d[1], r->dir_z = s->d[2];
    r->tnear = s->tnear, r->tfar = s->tfar, r->time = 0.0f;
    r->mask = ~0u, r->id = 0, r->flags = 0;
}

void lanes_embree_trace1(const lanes_embree *e, const lanes_ray *rays, size_t n, lanes_hit *hits)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    unsigned csr = lanes_fp_fast_enter();
    for (size_t i = 0; i < n; i++) {
        struct RTCRayHit rh;
        memset(&rh, 0, sizeof rh);
        fill_ray(&rh.ray, &rays[i]);
        rh.hit.geomID = rh.hit.primID = rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(e->scene, &ctx, &rh);
        hits[i] = make_hit(rh.hit.geomID, rh.hit.primID, rh.ray.tfar, rh.hit.u, rh.hit.v);
    }
    lanes_fp_restore(csr);
}

static void paths_trace(void *ctx, const lanes_ray *rays, size_t n, lanes_hit *hits)
{
    lanes_embree_trace_stream(ctx, rays, n, hits);
}

static void paths_occluded(void *ctx, const lanes_ray *rays, size_t n, uint8_t *occluded)
{
    lanes_embree_occluded_stream(ctx, rays, n, occluded);
}

lanes_paths_intersector lanes_embree_paths_intersector(const lanes_embree *e)
{
    return (lanes_paths_intersector){"embree", (void *)e, paths_trace, paths_occluded};
}

/* A stream of n rays in one rtcIntersect1M / rtcOccluded1M call, through a
 * copy in Embree's layout (on the stack for a few rays). */
enum { STREAM_STACK_RAYS = 16 };

void lanes_embree_trace_stream(const lanes_embree *e, const lanes_ray *rays, size_t n, lanes_hit *hits)
{
    struct RTCRayHit stack[STREAM_STACK_RAYS], *rh = n <= STREAM_STACK_RAYS ? stack : malloc(n * sizeof *rh);
    if (!rh) {
        lanes_embree_trace1(e, rays, n, hits); /* no memory for the copy: one at a time */
        return;
    }
    for (size_t i = 0; i < n; i++) {
        memset(&rh[i], 0, sizeof rh[i]);
        fill_ray(&rh[i].ray, &rays[i]);
        rh[i].hit.geomID = rh[i].hit.primID = rh[i].hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    }
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    unsigned csr = lanes_fp_fast_enter();
    if (n == 1) rtcIntersect1(e->scene, &ctx, rh);
    else if (n > 1) rtcIntersect1M(e->scene, &ctx, rh, (unsigned)n, sizeof *rh);
    lanes_fp_restore(csr);
    for (size_t i = 0; i < n; i++) hits[i] = make_hit(rh[i].hit.geomID, rh[i].hit.primID, rh[i].ray.tfar, rh[i].hit.u, rh[i].hit.v);
    if (rh != stack) free(rh);
}

void lanes_embree_occluded_stream(const lanes_embree *e, const lanes_ray *rays, size_t n, uint8_t *occluded)
{
    struct RTCRay stack[STREAM_STACK_RAYS], *r = n <= STREAM_STACK_RAYS ? stack : malloc(n * sizeof *r);
    if (!r) {
        lanes_embree_occluded1(e, rays, n, occluded);
        return;
    }
    for (size_t i = 0; i < n; i++) fill_ray(&r[i], &rays[i]);
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    unsigned csr = lanes_fp_fast_enter();
    if (n == 1) rtcOccluded1(e->scene, &ctx, r);
    else if (n > 1) rtcOccluded1M(e->scene, &ctx, r, (unsigned)n, sizeof *r);
    lanes_fp_restore(csr);
    for (size_t i = 0; i < n; i++) occluded[i] = r[i].tfar == -INFINITY;
    if (r != stack) free(r);
}

void lanes_embree_occluded1(const lanes_embree *e, const lanes_ray *rays, size_t n,
                            uint8_t *occluded)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    unsigned csr = lanes_fp_fast_enter();
    for (size_t i = 0; i < n; i++) {
        struct RTCRay r;
        fill_ray(&r, &rays[i]);
        rtcOccluded1(e->scene, &ctx, &r);
        occluded[i] = r.tfar == -INFINITY;
    }
    lanes_fp_restore(csr);
}
