/* The public API as a user sees it: only <lanes/lanes.h>, linked against the
 * shared library. Checks devices and their config strings, every argument
 * error (status, message, callback), accels from arrays, the three query
 * forms against a brute-force double-precision reference and against each
 * other at every instruction set this CPU runs and every accuracy mode,
 * invalid rays, packets of any size, accels over the caller's arrays
 * (shared, not copied) against copied ones bit for bit, the sizes each
 * accuracy mode traces or refuses, and concurrent queries of one accel.
 *
 *   test_api [--expect-refused SET]   (SET must be refused as the CPU lacking it)
 */
#define _POSIX_C_SOURCE 200809L /* setenv */
#include <lanes/lanes.h>

#include "harness.h" /* beside this file: the test sees no other lanes header */

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const modes[] = {"fast", "default", "robust"};

/* ------------------------------------------------------------- scene */

static harness_rng rng = {0x9e3779b97f4a7c15ull};
static double rnd(void) /* [0, 1) */
{
    return harness_uniform(&rng);
}

typedef struct mesh {
    float *v;
    uint32_t *idx;
    size_t nv, nt;
} mesh;

/* A bumpy 24x24 height field (shared vertices, like a real mesh), 300
 * loose random triangles above it, and triangles of no area among the
 * height field's (a repeated vertex; three points on a line), which the
 * copied and the shared leaf layouts must both leave out. */
static mesh make_mesh(void)
{
    mesh m;
    const int g = 24;
    const size_t loose = 300, flat = 24;
    m.nv = (size_t)(g + 1) * (g + 1) + 3 * loose + 3;
    m.nt = (size_t)2 * g * g + loose + flat;
    m.v = malloc(m.nv * 3 * sizeof(float));
    m.idx = malloc(m.nt * 3 * sizeof(uint32_t));
    size_t nv = 0, nt = 0;
    for (int y = 0; y <= g; y++)
        for (int x = 0; x <= g; x++) {
            m.v[3 * nv] = (float)x / g * 4.0f - 2.0f;
            m.v[3 * nv + 1] = 0.2f * sinf(3.0f * (float)x / g) * cosf(5.0f * (float)y / g);
            m.v[3 * nv + 2] = (float)y / g * 4.0f - 2.0f;
            nv++;
        }
    for (int y = 0; y < g; y++)
        for (int x = 0; x < g; x++) {
            uint32_t a = (uint32_t)(y * (g + 1) + x), b = a + 1, c = a + (uint32_t)g + 1, d = c + 1;
            uint32_t q[6] = {a, b, d, a, d, c};
            memcpy(m.idx + 3 * nt, q, sizeof q);
            nt += 2;
        }
    for (size_t i = 0; i < loose; i++) {
        float cx = (float)(rnd() * 4 - 2), cy = (float)(rnd() * 1.5 + 0.3), cz = (float)(rnd() * 4 - 2);
        for (int k = 0; k < 3; k++) {
            m.v[3 * nv] = cx + (float)(rnd() - 0.5) * 0.4f;
            m.v[3 * nv + 1] = cy + (float)(rnd() - 0.5) * 0.4f;
            m.v[3 * nv + 2] = cz + (float)(rnd() - 0.5) * 0.4f;
            m.idx[3 * nt + (size_t)k] = (uint32_t)nv++;
        }
        nt++;
    }
    const float line[9] = {-1.25f, 0.0f, -0.75f, -0.875f, 0.0625f, -0.5f, -0.5f, 0.125f, -0.25f}; /* exact */
    memcpy(m.v + 3 * nv, line, sizeof line);
    for (size_t i = 0; i < flat; i++) {
        uint32_t a = (uint32_t)(i * 17 % ((size_t)g * g)), b = a + 1;
        uint32_t q[3] = {a, b, a};
        if (i % 3 == 0) q[0] = (uint32_t)nv, q[1] = (uint32_t)nv + 1, q[2] = (uint32_t)nv + 2;
        memcpy(m.idx + 3 * nt, q, sizeof q);
        nt++;
    }
    nv += 3;
    return m;
}

/* Brute force in double: the closest hit, and how close the decision was
 * (smallest barycentric margin of the hit, gap to the next t), so that rays
 * on an edge or at a tie are not counted as disagreements. */
typedef struct ref_hit {
    double t, margin, gap;
    uint32_t prim;
} ref_hit;

static ref_hit brute(const mesh *m, const double o[3], const double d[3], double tnear, double tfar)
{
    ref_hit r = {INFINITY, INFINITY, INFINITY, LANES_INVALID_ID};
    double second = INFINITY;
    for (size_t i = 0; i < m->nt; i++) {
        double p[3][3];
        for (int k = 0; k < 3; k++)
            for (int a = 0; a < 3; a++) p[k][a] = m->v[3 * m->idx[3 * i + (size_t)k] + (size_t)a];
        double e1[3], e2[3], s[3], pv[3], qv[3];
        for (int a = 0; a < 3; a++) e1[a] = p[1][a] - p[0][a], e2[a] = p[2][a] - p[0][a], s[a] = o[a] - p[0][a];
        pv[0] = d[1] * e2[2] - d[2] * e2[1], pv[1] = d[2] * e2[0] - d[0] * e2[2], pv[2] = d[0] * e2[1] - d[1] * e2[0];
        double det = e1[0] * pv[0] + e1[1] * pv[1] + e1[2] * pv[2];
        if (det == 0) continue;
        double u = (s[0] * pv[0] + s[1] * pv[1] + s[2] * pv[2]) / det;
        qv[0] = s[1] * e1[2] - s[2] * e1[1], qv[1] = s[2] * e1[0] - s[0] * e1[2], qv[2] = s[0] * e1[1] - s[1] * e1[0];
        double v = (d[0] * qv[0] + d[1] * qv[1] + d[2] * qv[2]) / det;
        double t = (e2[0] * qv[0] + e2[1] * qv[1] + e2[2] * qv[2]) / det;
        double margin = fmin(fmin(u, v), 1 - u - v);
        if (margin < -1e-4 || t < tnear - 1e-4 || t > tfar + 1e-4) continue;
        if (margin < 0 || t < tnear || t > tfar) {
            r.margin = fmin(r.margin, fabs(margin)); /* just outside: a float test may count it */
            continue;
        }
        if (t < r.t) {
            second = r.t;
            r.t = t;
            r.prim = (uint32_t)i;
            r.margin = fmin(r.margin, margin);
        } else if (t < second) {
            second = t;
        }
    }
    r.gap = second - r.t;
    return r;
}

typedef struct rayset {
    float *ox, *oy, *oz, *dx, *dy, *dz, *tn, *tf;
    size_t n;
} rayset;

static rayset alloc_rays(size_t n)
{
    rayset r;
    float **arrays[8] = {&r.ox, &r.oy, &r.oz, &r.dx, &r.dy, &r.dz, &r.tn, &r.tf};
    for (int i = 0; i < 8; i++) *arrays[i] = calloc(n ? n : 1, sizeof(float));
    r.n = n;
    return r;
}

static void free_rays(rayset *r)
{
    free(r->ox), free(r->oy), free(r->oz), free(r->dx), free(r->dy), free(r->dz), free(r->tn), free(r->tf);
}

static lanes_rays_soa soa(const rayset *r)
{
    lanes_rays_soa s = {r->ox, r->oy, r->oz, r->dx, r->dy, r->dz, r->tn, r->tf};
    return s;
}

/* Half camera rays in 8x8 screen tiles (coherent), half random rays from
 * random points toward the mesh (incoherent). */
static rayset make_rays(size_t n)
{
    rayset r = alloc_rays(n);
    for (size_t i = 0; i < n; i++) {
        if (i < n / 2) {
            /* a 64-pixel-wide screen looking at the mesh's centre */
            size_t tile = i / 64, in = i % 64;
            double px = (double)(tile % 8 * 8 + in % 8) / 64.0 - 0.5;
            double py = (double)(tile / 8 * 8 + in / 8) / 64.0 - 0.5;
            r.ox[i] = 0.0f, r.oy[i] = 3.0f, r.oz[i] = -6.0f;
            r.dx[i] = (float)(px * 0.8), r.dy[i] = (float)(-0.5 + py * 0.8), r.dz[i] = 1.0f;
        } else {
            r.ox[i] = (float)(rnd() * 8 - 4), r.oy[i] = (float)(rnd() * 3 + 0.5), r.oz[i] = (float)(rnd() * 8 - 4);
            r.dx[i] = (float)(rnd() * 2 - 1), r.dy[i] = (float)(rnd() * 2 - 1.3), r.dz[i] = (float)(rnd() * 2 - 1);
        }
        r.tn[i] = 0.0f;
        r.tf[i] = (i % 7 == 3) ? 2.5f : INFINITY; /* some bounded intervals */
    }
    return r;
}

typedef struct results {
    float *t, *u, *v;
    uint32_t *prim;
    uint8_t *occ;
} results;

static results alloc_results(size_t n)
{
    results r = {calloc(n + 1, sizeof(float)), calloc(n + 1, sizeof(float)), calloc(n + 1, sizeof(float)),
                 calloc(n + 1, sizeof(uint32_t)), calloc(n + 1, 1)};
    return r;
}

static void free_results(results *r) { free(r->t), free(r->u), free(r->v), free(r->prim), free(r->occ); }

static lanes_hits_soa hits_of(results *r)
{
    lanes_hits_soa h = {r->t, r->u, r->v, r->prim};
    return h;
}

/* --------------------------------------------------------- error paths */

static int callback_calls;
static lanes_status callback_status;
static char callback_message[512];

static void on_error(void *user, lanes_status status, const char *message)
{
    (void)user;
    callback_calls++;
    callback_status = status;
    snprintf(callback_message, sizeof callback_message, "%s", message);
}

static void expect_error(lanes_status got, lanes_status want, const char *needle, const char *what)
{
    const char *msg = lanes_last_error_message();
    CHECK(got == want, "%s: status %d (%s), want %d (%s)", what, (int)got, lanes_status_name(got),
          (int)want, lanes_status_name(want));
    CHECK(strstr(msg, needle) != NULL, "%s: message \"%s\" does not mention \"%s\"", what, msg, needle);
}

static void test_devices(const char *expect_refused)
{
    char want[32];
    snprintf(want, sizeof want, "%d.%d.%d", LANES_VERSION_MAJOR, LANES_VERSION_MINOR, LANES_VERSION_PATCH);
    CHECK(strcmp(lanes_version(), want) == 0, "lanes_version() %s, header %s", lanes_version(), want);

    lanes_device d = NULL;
    CHECK(lanes_device_create(NULL, &d) == LANES_OK && d, "default device: %s", lanes_last_error_message());
    lanes_device_info info;
    CHECK(lanes_device_get_info(d, &info) == LANES_OK, "info");
    printf("default device: %s, %d lanes, %d-wide nodes, accuracy %s\n", info.isa, info.lanes,
           info.node_width, info.accuracy);
    lanes_device_release(d);

    CHECK(lanes_device_create(" threads = 1 , accuracy=robust,isa=scalar", &d) == LANES_OK,
          "spaced config: %s", lanes_last_error_message());
    lanes_device_get_info(d, &info);
    CHECK(strcmp(info.isa, "scalar") == 0 && info.lanes == 1 && info.threads == 1 &&
              strcmp(info.accuracy, "robust") == 0,
          "config not applied: %s %d %d %s", info.isa, info.lanes, info.threads, info.accuracy);
    lanes_device_release(d);

    struct {
        const char *config, *needle;
        lanes_status want;
    } bad[] = {
        {"isa=avx513", "avx513", LANES_ERR_UNKNOWN_ISA},
        {"threads=-1", "threads=-1", LANES_ERR_BAD_INPUT},
        {"threads=two", "threads=two", LANES_ERR_BAD_INPUT},
        {"accuracy=exact", "accuracy=exact", LANES_ERR_BAD_INPUT},
        {"node_width=6", "node_width=6", LANES_ERR_BAD_INPUT},
        {"node_width=", "node_width=", LANES_ERR_BAD_INPUT},
        {"colour=blue", "colour", LANES_ERR_BAD_INPUT},
        {"isa", "key=value", LANES_ERR_BAD_INPUT},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        d = (lanes_device)&d; /* must be reset to NULL */
        lanes_status st = lanes_device_create(bad[i].config, &d);
        expect_error(st, bad[i].want, bad[i].needle, bad[i].config);
        CHECK(d == NULL, "%s: device not NULL on error", bad[i].config);
    }
    expect_error(lanes_device_create(NULL, NULL), LANES_ERR_BAD_INPUT, "NULL", "NULL out");

    if (expect_refused) {
        char config[64];
        snprintf(config, sizeof config, "isa=%s", expect_refused);
        lanes_status st = lanes_device_create(config, &d);
        expect_error(st, LANES_ERR_CPU_LACKS, "cannot run", config);
        printf("refused as it must be: %s: %s\n", config, lanes_last_error_message());
    }
}

static void test_argument_errors(const mesh *m)
{
    /* the process-wide set choice reports through the last error too */
    char buf[256];
    expect_error(lanes_set_isa_by_name("avx513", buf, sizeof buf), LANES_ERR_UNKNOWN_ISA, "avx513", "set_isa_by_name");
    CHECK(strcmp(buf, lanes_last_error_message()) == 0, "set_isa_by_name: buffer \"%s\"", buf);
    expect_error(lanes_set_isa((lanes_isa)99, NULL, 0), LANES_ERR_UNKNOWN_ISA, "unknown", "set_isa(99)");
    expect_error(lanes_set_max_isa((lanes_isa)99, NULL, 0), LANES_ERR_UNKNOWN_ISA, "valid names", "set_max_isa(99)");
    lanes_device d;
    lanes_device_create(NULL, &d);
    lanes_device_set_error_callback(d, on_error, NULL);
    lanes_accel a = (lanes_accel)&a;

    callback_calls = 0;
    expect_error(lanes_accel_create(d, NULL, m->nv, m->idx, m->nt, &a), LANES_ERR_BAD_INPUT, "vertices", "NULL vertices");
    CHECK(a == NULL, "accel not NULL on error");
    CHECK(callback_calls == 1 && callback_status == LANES_ERR_BAD_INPUT &&
              strcmp(callback_message, lanes_last_error_message()) == 0,
          "callback: %d calls, status %d, \"%s\"", callback_calls, (int)callback_status, callback_message);
    expect_error(lanes_accel_create(d, m->v, m->nv, NULL, m->nt, &a), LANES_ERR_BAD_INPUT, "indices", "NULL indices");
    expect_error(lanes_accel_create(d, m->v, m->nv, m->idx, 0, &a), LANES_ERR_BAD_INPUT, "no triangles", "0 triangles");
    expect_error(lanes_accel_create(d, m->v, m->nv - 1, m->idx, m->nt, &a), LANES_ERR_BAD_INPUT,
                 "vertex index", "index out of range");
    expect_error(lanes_accel_create(NULL, m->v, m->nv, m->idx, m->nt, &a), LANES_ERR_BAD_INPUT, "device", "NULL device");
    CHECK(callback_calls == 4, "callback calls %d, want 4 (not for a NULL device)", callback_calls);
    expect_error(lanes_accel_create_shared(d, NULL, m->nv, m->idx, m->nt, &a), LANES_ERR_BAD_INPUT, "vertices",
                 "shared: NULL vertices");
    expect_error(lanes_accel_create_shared(d, m->v, m->nv - 1, m->idx, m->nt, &a), LANES_ERR_BAD_INPUT,
                 "vertex index", "shared: index out of range");
    /* The gathers' 32-bit offsets bound a shared accel, not a copied one
     * (the vertex count only bounds the indices: nothing past them is read). */
    expect_error(lanes_accel_create_shared(d, m->v, (size_t)INT32_MAX, m->idx, m->nt, &a), LANES_ERR_BAD_INPUT,
                 "32-bit offsets", "shared: 2^31-1 vertices");
    CHECK(a == NULL, "shared accel not NULL on error");
    CHECK(lanes_accel_create(d, m->v, (size_t)INT32_MAX, m->idx, m->nt, &a) == LANES_OK,
          "copied accel of 2^31-1 vertices: %s", lanes_last_error_message());
    lanes_accel_release(a);

    /* The status comes from where the failure was found: an accel that
     * cannot fit is out of memory, a limit that is no size is bad input. */
    setenv("LANES_MEMORY_LIMIT", "1K", 1);
    expect_error(lanes_accel_create(d, m->v, m->nv, m->idx, m->nt, &a), LANES_ERR_OUT_OF_MEMORY,
                 "LANES_MEMORY_LIMIT allows", "accel over LANES_MEMORY_LIMIT=1K");
    setenv("LANES_MEMORY_LIMIT", "lots", 1);
    expect_error(lanes_accel_create(d, m->v, m->nv, m->idx, m->nt, &a), LANES_ERR_BAD_INPUT,
                 "'lots' is not a size", "LANES_MEMORY_LIMIT=lots");
    unsetenv("LANES_MEMORY_LIMIT");

    /* A triangle with a NaN vertex is left out and never hit, copied or
     * shared (the NaN triangle comes first, so a shared leaf that gathered
     * it would answer it). */
    float tri[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    float nan_tri[18];
    memcpy(nan_tri, tri, sizeof tri);
    memcpy(nan_tri + 9, tri, sizeof tri);
    nan_tri[0] = NAN;
    uint32_t idx[6] = {0, 1, 2, 3, 4, 5};
    lanes_accel_info ai;
    lanes_ray1 ray = {{0.2f, 0.2f, -1}, {0, 0, 1}, 0, INFINITY};
    lanes_hit1 hit;
    CHECK(lanes_accel_create_shared(d, nan_tri, 6, idx, 2, &a) == LANES_OK, "shared, NaN vertex: %s",
          lanes_last_error_message());
    lanes_accel_get_info(a, &ai);
    CHECK(ai.triangles == 2 && ai.skipped == 1, "shared, NaN triangle: %zu triangles, %zu skipped", ai.triangles,
          ai.skipped);
    CHECK(lanes_intersect1(a, &ray, &hit) == LANES_OK && hit.prim_id == 1 && fabsf(hit.t - 1.0f) < 1e-6f,
          "shared: hit the finite triangle: prim %u t %g", hit.prim_id, hit.t);
    lanes_accel_release(a);
    CHECK(lanes_accel_create(d, nan_tri, 6, idx, 2, &a) == LANES_OK, "NaN vertex: %s", lanes_last_error_message());
    lanes_accel_get_info(a, &ai);
    CHECK(ai.triangles == 2 && ai.skipped == 1, "NaN triangle: %zu triangles, %zu skipped", ai.triangles, ai.skipped);
    CHECK(lanes_intersect1(a, &ray, &hit) == LANES_OK && hit.prim_id == 1 && fabsf(hit.t - 1.0f) < 1e-6f,
          "hit the finite triangle: prim %u t %g", hit.prim_id, hit.t);
    bool occ = false;
    CHECK(lanes_occluded1(a, &ray, &occ) == LANES_OK && occ, "occluded");
    ray.tfar = 0.5f;
    CHECK(lanes_occluded1(a, &ray, &occ) == LANES_OK && !occ, "not occluded before tfar");
    ray.tnear = 2.0f, ray.tfar = 1.0f;
    CHECK(lanes_intersect1(a, &ray, &hit) == LANES_OK && hit.prim_id == LANES_INVALID_ID && isinf(hit.t),
          "tnear > tfar is an empty interval");

    /* Invalid rays: a miss, and an error naming the ray. */
    callback_calls = 0;
    ray = (lanes_ray1){{NAN, 0, -1}, {0, 0, 1}, 0, INFINITY};
    expect_error(lanes_intersect1(a, &ray, &hit), LANES_ERR_BAD_INPUT, "ray 0", "NaN ray");
    CHECK(hit.prim_id == LANES_INVALID_ID, "a NaN ray misses");
    ray = (lanes_ray1){{0.2f, 0.2f, -1}, {0, 0, 0}, 0, INFINITY};
    expect_error(lanes_occluded1(a, &ray, &occ), LANES_ERR_BAD_INPUT, "invalid ray", "zero direction");
    CHECK(!occ, "an invalid ray is not occluded");
    CHECK(callback_calls == 2, "callback on invalid rays: %d", callback_calls);

    expect_error(lanes_intersect1(NULL, &ray, &hit), LANES_ERR_BAD_INPUT, "accel", "NULL accel");
    expect_error(lanes_intersect1(a, NULL, &hit), LANES_ERR_BAD_INPUT, "ray", "NULL ray");
    expect_error(lanes_intersect1(a, &ray, NULL), LANES_ERR_BAD_INPUT, "result", "NULL hit");
    lanes_rays_soa rs = {0};
    results r = alloc_results(1);
    lanes_hits_soa hs = hits_of(&r);
    expect_error(lanes_intersect_stream(a, &rs, 1, &hs), LANES_ERR_BAD_INPUT, "array", "NULL ray array");
    expect_error(lanes_occluded_packet(a, &rs, 1, r.occ), LANES_ERR_BAD_INPUT, "array", "NULL packet array");
    hs.prim_id = NULL;
    rayset one = make_rays(1);
    rs = soa(&one);
    expect_error(lanes_intersect_packet(a, &rs, 1, &hs), LANES_ERR_BAD_INPUT, "result", "NULL prim_id");
    hs.prim_id = r.prim;
    hs.u = hs.v = NULL; /* allowed */
    CHECK(lanes_intersect_stream(a, &rs, 1, &hs) == LANES_OK, "u, v may be NULL");
    CHECK(lanes_intersect_stream(a, &rs, 0, &hs) == LANES_OK && lanes_intersect_packet(a, &rs, 0, &hs) == LANES_OK,
          "n = 0");
    CHECK(lanes_intersect_stream(a, NULL, 0, NULL) == LANES_OK && lanes_occluded_packet(a, NULL, 0, NULL) == LANES_OK,
          "n = 0 needs no arrays: %s", lanes_last_error_message());
    free_rays(&one);
    free_results(&r);

    lanes_accel_release(a);
    CHECK(lanes_accel_release(NULL) == LANES_OK && lanes_device_release(NULL) == LANES_OK, "release NULL");
    lanes_device_release(d);
}

/* ------------------------------------------------ queries at every set */

static void trace_all(lanes_accel a, const rayset *rays, results *stream, results *packet, results *one)
{
    lanes_rays_soa s = soa(rays);
    lanes_hits_soa hs = hits_of(stream), hp = hits_of(packet);
    CHECK(lanes_intersect_stream(a, &s, rays->n, &hs) == LANES_OK, "stream: %s", lanes_last_error_message());
    CHECK(lanes_intersect_packet(a, &s, rays->n, &hp) == LANES_OK, "packet: %s", lanes_last_error_message());
    CHECK(lanes_occluded_stream(a, &s, rays->n, stream->occ) == LANES_OK, "occluded stream");
    CHECK(lanes_occluded_packet(a, &s, rays->n, packet->occ) == LANES_OK, "occluded packet");
    for (size_t i = 0; i < rays->n; i++) {
        lanes_ray1 r = {{rays->ox[i], rays->oy[i], rays->oz[i]}, {rays->dx[i], rays->dy[i], rays->dz[i]},
                        rays->tn[i], rays->tf[i]};
        lanes_hit1 h;
        bool occ;
        lanes_intersect1(a, &r, &h);
        lanes_occluded1(a, &r, &occ);
        one->t[i] = h.t, one->u[i] = h.u, one->v[i] = h.v, one->prim[i] = h.prim_id;
        one->occ[i] = occ;
    }
}

/* Closest hits must agree bitwise in t and in whether they hit; the
 * triangle may differ only at a tie (two triangles at the same t, as on a
 * shared edge: the wide BVH and the BVH2 meet them in different orders). */
static bool same_hit(float ta, uint32_t pa, float tb, uint32_t pb)
{
    return memcmp(&ta, &tb, sizeof ta) == 0 && (pa == LANES_INVALID_ID) == (pb == LANES_INVALID_ID);
}

static size_t differences(const results *a, const results *b, size_t n, bool occlusion)
{
    size_t diff = 0;
    for (size_t i = 0; i < n; i++)
        if (occlusion ? a->occ[i] != b->occ[i] : !same_hit(a->t[i], a->prim[i], b->t[i], b->prim[i]))
            diff++;
    return diff;
}

/* Every output bit for bit: t, u, v, triangle and occlusion. */
static size_t not_identical(const results *a, const results *b, size_t n)
{
    size_t diff = 0;
    for (size_t i = 0; i < n; i++)
        diff += memcmp(&a->t[i], &b->t[i], sizeof(float)) || memcmp(&a->u[i], &b->u[i], sizeof(float)) ||
                memcmp(&a->v[i], &b->v[i], sizeof(float)) || a->prim[i] != b->prim[i] || a->occ[i] != b->occ[i];
    return diff;
}

/* An accel over the caller's arrays answers every query form as the copied
 * one does, bit for bit, and holds less. */
static void check_shared(const char *config, lanes_device d, const mesh *m, const rayset *rays,
                         const results *stream, const results *packet, const results *one, size_t copied_bytes)
{
    lanes_accel a;
    CHECK(lanes_accel_create_shared(d, m->v, m->nv, m->idx, m->nt, &a) == LANES_OK, "%s: shared accel: %s",
          config, lanes_last_error_message());
    if (!a) return;
    lanes_accel_info ai;
    lanes_accel_get_info(a, &ai);
    CHECK(ai.triangles == m->nt && ai.bytes < copied_bytes, "%s: shared accel: %zu triangles, %zu bytes (copied %zu)",
          config, ai.triangles, ai.bytes, copied_bytes);
    size_t n = rays->n;
    results s = alloc_results(n), p = alloc_results(n), o = alloc_results(n);
    trace_all(a, rays, &s, &p, &o);
    size_t ds = not_identical(stream, &s, n), dp = not_identical(packet, &p, n), d1 = not_identical(one, &o, n);
    CHECK(ds == 0 && dp == 0 && d1 == 0,
          "%s: the shared accel differs from the copied one on %zu stream, %zu packet, %zu single rays", config, ds,
          dp, d1);
    printf("%s %s: shared accel (%zu bytes, copied %zu) answers as the copied one, bit for bit\n",
           ds + dp + d1 == 0 ? "PASS" : "FAIL", config, ai.bytes, copied_bytes);
    free_results(&s), free_results(&p), free_results(&o);
    lanes_accel_release(a);
}

static void test_queries(const mesh *m)
{
    const size_t n = 6000;
    rayset rays = make_rays(n);
    ref_hit *ref = malloc(n * sizeof *ref);
    for (size_t i = 0; i < n; i++) {
        double o[3] = {rays.ox[i], rays.oy[i], rays.oz[i]}, d[3] = {rays.dx[i], rays.dy[i], rays.dz[i]};
        ref[i] = brute(m, o, d, rays.tn[i], rays.tf[i]);
    }
    results stream = alloc_results(n), packet = alloc_results(n), one = alloc_results(n);
    int sets_run = 0;
    for (int s = 0; s < LANES_ISA_COUNT * 3; s++) {
        /* every set at every node width; those below its lane count refused */
        const char *set_name = lanes_isa_name((lanes_isa)(s / 3));
        const int node_width = 4 << s % 3;
        lanes_device own;
        char config[96];
        snprintf(config, sizeof config, "isa=%s", set_name);
        if (lanes_device_create(config, &own) != LANES_OK) {
            if (node_width == 4) printf("SKIP %s: %s\n", set_name, lanes_last_error_message());
            continue;
        }
        lanes_device_info own_info;
        lanes_device_get_info(own, &own_info);
        lanes_device_release(own);
        for (size_t md = 0; md < 3; md++) {
            snprintf(config, sizeof config, "isa=%s,node_width=%d,accuracy=%s,threads=2", set_name, node_width,
                     modes[md]);
            lanes_device d;
            lanes_status st = lanes_device_create(config, &d);
            if (node_width < own_info.lanes) {
                expect_error(st, LANES_ERR_BAD_INPUT, "node_width", config);
                break;
            }
            CHECK(st == LANES_OK, "%s: %s", config, lanes_last_error_message());
            if (st != LANES_OK) break;
            if (md == 0 && node_width == own_info.node_width) sets_run++;
            lanes_accel a;
            CHECK(lanes_accel_create(d, m->v, m->nv, m->idx, m->nt, &a) == LANES_OK, "%s: accel: %s", config,
                  lanes_last_error_message());
            lanes_accel_info ai;
            lanes_device_info di;
            lanes_accel_get_info(a, &ai);
            lanes_device_get_info(d, &di);
            CHECK(ai.node_width == di.node_width && di.node_width == node_width && ai.triangles == m->nt &&
                      ai.skipped == 0,
                  "%s: node width %d (device %d), %zu triangles", config, ai.node_width, di.node_width, ai.triangles);
            trace_all(a, &rays, &stream, &packet, &one);
            check_shared(config, d, m, &rays, &stream, &packet, &one, ai.bytes);

            size_t wrong = 0, close_calls = 0, hits = 0, occ_wrong = 0;
            for (size_t i = 0; i < n; i++) {
                bool ambiguous = ref[i].margin < 1e-4 || ref[i].gap < 1e-4 * fmax(1.0, ref[i].t);
                bool agree = stream.prim[i] == ref[i].prim &&
                             (ref[i].prim == LANES_INVALID_ID || fabs(stream.t[i] - ref[i].t) <= 1e-4 * fmax(1.0, ref[i].t));
                if (ref[i].prim != LANES_INVALID_ID) hits++;
                if (!agree && ambiguous) close_calls++;
                else if (!agree) wrong++;
                if ((stream.occ[i] != 0) != (stream.prim[i] != LANES_INVALID_ID)) occ_wrong++;
            }
            CHECK(wrong == 0, "%s: %zu of %zu rays disagree with brute force (not at an edge or tie)", config, wrong, n);
            CHECK(hits > n / 5 && hits < n, "%s: the rays hit %zu of %zu times: not a useful test", config, hits, n);
            CHECK(occ_wrong == 0, "%s: occlusion disagrees with the closest hit on %zu rays", config, occ_wrong);
            size_t dp = differences(&stream, &packet, n, false), d1 = differences(&stream, &one, n, false);
            size_t op = differences(&stream, &packet, n, true), o1 = differences(&stream, &one, n, true);
            CHECK(dp == 0 && d1 == 0 && op == 0 && o1 == 0,
                  "%s: packet/single differ from the stream on %zu/%zu closest and %zu/%zu occlusion rays", config,
                  dp, d1, op, o1);
            printf("%s %s: %zu rays, %zu hits, %zu at an edge or tie differ from brute force; stream, packet "
                   "and single agree\n",
                   wrong == 0 ? "PASS" : "FAIL", config, n, hits, close_calls);

            /* Packets of every awkward size, rays beyond 1024 included. */
            size_t sizes[] = {1, 7, 1023, 1024, 1025, 2055};
            for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; k++) {
                size_t c = sizes[k];
                lanes_rays_soa rs = {rays.ox + 100, rays.oy + 100, rays.oz + 100, rays.dx + 100,
                                     rays.dy + 100, rays.dz + 100, rays.tn + 100, rays.tf + 100};
                results r = alloc_results(c);
                lanes_hits_soa h = hits_of(&r);
                lanes_intersect_packet(a, &rs, c, &h);
                size_t diff = 0;
                for (size_t i = 0; i < c; i++)
                    if (!same_hit(r.t[i], r.prim[i], stream.t[100 + i], stream.prim[100 + i])) diff++;
                CHECK(diff == 0, "%s: a packet call of %zu rays differs on %zu", config, c, diff);
                free_results(&r);
            }
            lanes_accel_release(a);
            lanes_device_release(d);
        }
    }
    CHECK(sets_run >= 1, "no instruction set ran");

    /* A NaN ray inside a stream and a packet: named, a miss, the rest as before. */
    lanes_device d;
    lanes_device_create(NULL, &d);
    lanes_accel a;
    lanes_accel_create(d, m->v, m->nv, m->idx, m->nt, &a);
    lanes_rays_soa s = soa(&rays);
    lanes_hits_soa hs = hits_of(&stream);
    lanes_intersect_stream(a, &s, n, &hs);
    float saved = rays.dy[1500];
    rays.dy[1500] = NAN;
    results bad = alloc_results(n);
    lanes_hits_soa hb = hits_of(&bad);
    expect_error(lanes_intersect_stream(a, &s, n, &hb), LANES_ERR_BAD_INPUT, "ray 1500", "NaN in a stream");
    bad.prim[1500] = stream.prim[1500], bad.t[1500] = stream.t[1500];
    CHECK(differences(&stream, &bad, n, false) == 0, "a NaN ray changed other rays' results");
    expect_error(lanes_intersect_packet(a, &s, n, &hb), LANES_ERR_BAD_INPUT, "ray 1500", "NaN in a packet");
    CHECK(hb.prim_id[1500] == LANES_INVALID_ID, "the NaN ray in a packet misses");
    expect_error(lanes_occluded_packet(a, &s, n, bad.occ), LANES_ERR_BAD_INPUT, "ray 1500", "NaN, occluded packet");
    CHECK(bad.occ[1500] == 0, "the NaN ray is not occluded");
    rays.dy[1500] = saved;
    free_results(&bad);
    lanes_accel_release(a);
    lanes_device_release(d);

    free_results(&stream), free_results(&packet), free_results(&one);
    free(ref);
    free_rays(&rays);
}

/* ----------------------------------------------------------- threads */

typedef struct worker {
    lanes_accel accel;
    const rayset *rays;
    results out;
    bool packets;
    lanes_status st;
} worker;

static void *work(void *p)
{
    worker *w = p;
    lanes_rays_soa s = soa(w->rays);
    lanes_hits_soa h = hits_of(&w->out);
    for (int rep = 0; rep < 3 && w->st == LANES_OK; rep++)
        w->st = w->packets ? lanes_intersect_packet(w->accel, &s, w->rays->n, &h)
                           : lanes_intersect_stream(w->accel, &s, w->rays->n, &h);
    return NULL;
}

static void test_threads(const mesh *m)
{
    const size_t n = 20000;
    rayset rays = make_rays(n);
    lanes_device d;
    lanes_device_create(NULL, &d);
    lanes_accel a, shared;
    lanes_accel_create(d, m->v, m->nv, m->idx, m->nt, &a);
    lanes_accel_create_shared(d, m->v, m->nv, m->idx, m->nt, &shared);
    results alone = alloc_results(n);
    lanes_rays_soa s = soa(&rays);
    lanes_hits_soa h = hits_of(&alone);
    lanes_intersect_stream(a, &s, n, &h);

    enum { THREADS = 6 };
    worker w[THREADS];
    pthread_t th[THREADS];
    for (int i = 0; i < THREADS; i++) {
        w[i] = (worker){i < THREADS / 2 ? a : shared, &rays, alloc_results(n), i % 2 == 1, LANES_OK};
        pthread_create(&th[i], NULL, work, &w[i]);
    }
    for (int i = 0; i < THREADS; i++) pthread_join(th[i], NULL);
    for (int i = 0; i < THREADS; i++) {
        CHECK(w[i].st == LANES_OK, "thread %d: %s", i, lanes_status_name(w[i].st));
        size_t diff = differences(&alone, &w[i].out, n, false);
        CHECK(diff == 0, "thread %d (%s, %s accel) differs from the single-threaded result on %zu rays", i,
              w[i].packets ? "packets" : "stream", w[i].accel == shared ? "shared" : "copied", diff);
        free_results(&w[i].out);
    }
    printf("%d threads queried a copied and a shared accel at once: %s\n", THREADS,
           harness.failures ? "see above" : "same results");
    /* Accels keep their device: releasing the device first is allowed. */
    lanes_device_release(d);
    CHECK(lanes_intersect_stream(a, &s, 16, &h) == LANES_OK, "query after the device's release");
    lanes_accel_release(a);
    lanes_accel_release(shared);
    free_results(&alone);
    free_rays(&rays);
}

/* ------------------------------------------------------- scale limits */

/* One triangle in z = 0 spanning [-size, size]^2 (longest edge sqrt(5) size,
 * bounding-box diagonal 2 sqrt(2) size) on a device of the given config. */
static lanes_status triangle_accel(const char *config, float size, lanes_device *d, lanes_accel *a)
{
    float v[9] = {-size, -size, 0, size, -size, 0, 0, size, 0};
    uint32_t idx[3] = {0, 1, 2};
    *a = NULL;
    lanes_status st = lanes_device_create(config, d);
    if (st != LANES_OK) return st;
    return lanes_accel_create(*d, v, 3, idx, 1, a);
}

/* A ray straight down onto the triangle from height h: a hit at t = h. */
static lanes_status shoot_down(lanes_accel a, float h, lanes_hit1 *hit, lanes_status *stream_status)
{
    lanes_ray1 r = {{0.0f, 0.0f, h}, {0.0f, 0.0f, -1.0f}, 0.0f, INFINITY};
    lanes_status st = lanes_intersect1(a, &r, hit);
    /* the same ray in a stream of three, behind two that hit */
    float ox[3] = {0, 0, 0}, oz[3] = {1, 1, h}, dz[3] = {-1, -1, -1}, tn[3] = {0, 0, 0},
          tf[3] = {INFINITY, INFINITY, INFINITY}, t[3];
    uint32_t prim[3];
    lanes_rays_soa s = {ox, ox, oz, ox, ox, dz, tn, tf};
    lanes_hits_soa hs = {t, NULL, NULL, prim};
    *stream_status = lanes_intersect_stream(a, &s, 3, &hs);
    CHECK(prim[0] == 0 && prim[1] == 0 && prim[2] == hit->prim_id && t[2] == hit->t,
          "stream: rays beside the one from %g lost (prims %u %u), or it differs from the "
          "single ray (%u at %g against %u at %g)",
          (double)h, prim[0], prim[1], prim[2], (double)t[2], hit->prim_id, (double)hit->t);
    return st;
}

/* Every accuracy mode's float arithmetic holds a range of sizes (the
 * limits of build/accuracy.h): inside it, at every set, the answer is
 * right; outside it the accel or the ray is refused by name, never lost in
 * silence. The limits are computed here from the mode, not read back. */
static void test_scale_limits(void)
{
    int sets_run = 0;
    for (int s = 0; s < LANES_ISA_COUNT; s++) {
        const char *set_name = lanes_isa_name((lanes_isa)s);
        if (!lanes_isa_supported((lanes_isa)s)) continue;
        sets_run++;
        for (size_t md = 0; md < 3; md++) {
            const bool robust = md == 2;
            char config[96];
            snprintf(config, sizeof config, "isa=%s,accuracy=%s", set_name, modes[md]);
            lanes_device d;
            lanes_accel a;

            /* far rays: triangles of 1e10, default reach FLT_MAX / (6 * 5e20) */
            const float size = 1e10f;
            const double edge = sqrt(5.0) * size;
            const double reach = robust ? 1e18 : 3.4028234663852886e38 / (6.0 * edge * edge);
            lanes_status st = triangle_accel(config, size, &d, &a);
            CHECK(st == LANES_OK, "%s: accel of size %g: %s", config, (double)size, lanes_last_error_message());
            if (st == LANES_OK) {
                lanes_accel_info ai;
                lanes_accel_get_info(a, &ai);
                CHECK(fabs(ai.max_reach - reach) <= 1e-6 * reach, "%s: max_reach %g, want %g", config,
                      ai.max_reach, reach);
                lanes_hit1 hit;
                lanes_status ss;
                const float near = (float)(0.9 * reach), far = (float)(1.1 * reach);
                st = shoot_down(a, near, &hit, &ss);
                CHECK(st == LANES_OK && ss == LANES_OK && hit.prim_id == 0 &&
                          fabs(hit.t - near) <= 1e-6 * near,
                      "%s: ray from %g: %s, prim %u at t %g: %s", config, (double)near,
                      lanes_status_name(st), hit.prim_id, (double)hit.t, lanes_last_error_message());
                st = shoot_down(a, far, &hit, &ss);
                expect_error(st, LANES_ERR_BAD_INPUT, "too far from the mesh", config);
                expect_error(ss, LANES_ERR_BAD_INPUT, "ray 2 reaches", config);
                CHECK(hit.prim_id == LANES_INVALID_ID && isinf(hit.t), "%s: refused ray from %g: prim %u t %g",
                      config, (double)far, hit.prim_id, (double)hit.t);
            }
            lanes_accel_release(a);
            lanes_device_release(d);

            /* small meshes: a diagonal of 1.5 times the limit traces, of 0.5 is refused */
            const double min_diagonal = robust ? 1e-15 : 1e-11;
            for (int k = 0; k < 2; k++) {
                const double diagonal = (k ? 0.5 : 1.5) * min_diagonal;
                const float tiny = (float)(diagonal / (2.0 * sqrt(2.0)));
                st = triangle_accel(config, tiny, &d, &a);
                if (k) {
                    expect_error(st, LANES_ERR_BAD_INPUT, "diagonal", config);
                    CHECK(a == NULL, "%s: accel not NULL on error", config);
                } else {
                    CHECK(st == LANES_OK, "%s: mesh of diagonal %g: %s", config, diagonal,
                          lanes_last_error_message());
                    lanes_hit1 hit;
                    lanes_status ss;
                    const float h = 4.0f * tiny;
                    if (st == LANES_OK) st = shoot_down(a, h, &hit, &ss);
                    CHECK(st == LANES_OK && hit.prim_id == 0 && fabs(hit.t - h) <= 1e-6 * h,
                          "%s: diagonal %g, ray from %g: prim %u t %g", config, diagonal, (double)h,
                          hit.prim_id, (double)hit.t);
                }
                lanes_accel_release(a);
                lanes_device_release(d);
            }
        }
    }
    CHECK(sets_run >= 1, "no instruction set ran");
}

int main(int argc, char **argv)
{
    const char *expect_refused = NULL;
    for (int i = 1; i + 1 < argc; i++)
        if (strcmp(argv[i], "--expect-refused") == 0) expect_refused = argv[i + 1];
    printf("test_api: liblanes %s\n", lanes_version());
    mesh m = make_mesh();
    test_devices(expect_refused);
    test_argument_errors(&m);
    test_queries(&m);
    test_scale_limits();
    test_threads(&m);
    free(m.v);
    free(m.idx);
    return harness_summary("test_api");
}
