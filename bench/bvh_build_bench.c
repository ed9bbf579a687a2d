/* BVH build time, lanes against Embree, on the same generated triangles.
 *
 *   bench_bvh_build [--runs N] [--mesh sphere|soup|both] [--threads-only all|1]
 *                   [--bins K] [--no-high] [--lanes-only] [--cpu] [sizes...]
 *
 * For each mesh and size: the lanes BVH2 build, each wide BVH as the
 * library builds it for its width (lanes_wbvh_build: a BVH2 with the SAH by
 * blocks, collapsed; widths 4, 8, 16), and Embree's rtcCommitScene at the
 * default (medium) and high build quality, with all threads and with one;
 * medians of N runs after one warm-up run, the builders taking turns run by
 * run; ratios lanes / Embree (b2/med: BVH2 build over Embree medium; w8/med:
 * the whole 8-wide build over Embree medium; b2/high: BVH2 over Embree high),
 * medians of the per-run ratios. Times are wall clock, in ms.
 *
 * Embree builds its own BVH4/BVH8 with its best ISA on this CPU; lanes is
 * compiled for the x86-64 baseline. */
#define _POSIX_C_SOURCE 200809L

#include <embree3/rtcore.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "build/bvh.h"

#define LANES_PI 3.14159265358979323846
#include "simd/isa.h"

/* --cpu: process CPU time instead of wall clock, for tuning on a busy
 * machine. Only with --threads-only 1, where it is the build's own time
 * (Embree's threads=1 device still runs the build on a TBB worker, so the
 * calling thread's CPU time would miss it). */
static clockid_t g_clock = CLOCK_MONOTONIC;

static double now(void)
{
    struct timespec ts;
    clock_gettime(g_clock, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* SplitMix64: the same meshes on every machine. */
static uint64_t rng_state;
static uint64_t rng_next(void)
{
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}
static float rng_float(void) { return (float)(rng_next() >> 40) * (1.0f / 16777216.0f); }

/* A UV sphere of about n triangles whose radius varies by a few percent per
 * vertex: a closed surface mesh, the shape of most scanned models. */
static float *make_sphere(size_t n, size_t *count)
{
    size_t slices = (size_t)sqrt((double)n);
    size_t stacks = n / (2 * slices);
    if (stacks < 2) stacks = 2;
    size_t nv = (stacks + 1) * slices;
    float *vx = malloc(nv * 3 * sizeof(float));
    float *v = malloc(stacks * slices * 2 * 9 * sizeof(float));
    if (!vx || !v) exit(1);
    rng_state = 1;
    for (size_t i = 0; i <= stacks; i++) {
        double th = LANES_PI * (double)i / (double)stacks;
        for (size_t j = 0; j < slices; j++) {
            double ph = 2.0 * LANES_PI * (double)j / (double)slices;
            double r = 1.0 + 0.03 * (rng_float() - 0.5);
            float *p = vx + 3 * (i * slices + j);
            p[0] = (float)(r * sin(th) * cos(ph));
            p[1] = (float)(r * cos(th));
            p[2] = (float)(r * sin(th) * sin(ph));
        }
    }
    size_t t = 0;
    for (size_t i = 0; i < stacks; i++)
        for (size_t j = 0; j < slices; j++) {
            size_t a = i * slices + j, b = i * slices + (j + 1) % slices;
            size_t c = a + slices, d = b + slices;
            size_t tri[2][3] = {{a, c, b}, {b, c, d}};
            for (int k = 0; k < 2; k++) {
                for (int m = 0; m < 3; m++) memcpy(v + 9 * t + 3 * m, vx + 3 * tri[k][m], 12);
                t++;
            }
        }
    free(vx);
    *count = t;
    return v;
}

/* n random triangles of size ~ the mean spacing, uniform in the unit cube. */
static float *make_soup(size_t n, size_t *count)
{
    float *v = malloc(n * 9 * sizeof(float));
    if (!v) exit(1);
    rng_state = 2;
    float s = 2.0f / cbrtf((float)n);
    for (size_t i = 0; i < n; i++) {
        float c[3] = {rng_float(), rng_float(), rng_float()};
        for (int m = 0; m < 3; m++)
            for (int a = 0; a < 3; a++) v[9 * i + 3 * m + a] = c[a] + s * (rng_float() - 0.5f);
    }
    *count = n;
    return v;
}

static double embree_build(RTCDevice dev, const lanes_scene *sc, enum RTCBuildQuality q)
{
    RTCScene scene = rtcNewScene(dev);
    rtcSetSceneBuildQuality(scene, q);
    RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(g, q);
    size_t n = sc->triangle_count;
    float *vb = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                        3 * sizeof(float), 3 * n);
    unsigned *ib = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                           3 * sizeof(unsigned), n);
    if (!vb || !ib) {
        fprintf(stderr, "embree: buffer allocation failed\n");
        exit(1);
    }
    memcpy(vb, sc->verts, 9 * n * sizeof(float));
    for (size_t i = 0; i < 3 * n; i++) ib[i] = (unsigned)i;
    rtcCommitGeometry(g);
    rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
    double t0 = now();
    rtcCommitScene(scene);
    double t = now() - t0;
    if (rtcGetDeviceError(dev) != RTC_ERROR_NONE) {
        fprintf(stderr, "embree: commit failed\n");
        exit(1);
    }
    rtcReleaseScene(scene);
    return t;
}

int main(int argc, char **argv)
{
    int runs = 5, bins = 16;
    const char *mesh = "both", *only = NULL;
    int high = 1, embree = 1;
    size_t sizes[16];
    int nsizes = 0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--runs") && i + 1 < argc)
            runs = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--mesh") && i + 1 < argc)
            mesh = argv[++i];
        else if (!strcmp(argv[i], "--threads-only") && i + 1 < argc)
            only = argv[++i];
        else if (!strcmp(argv[i], "--bins") && i + 1 < argc)
            bins = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--no-high"))
            high = 0;
        else if (!strcmp(argv[i], "--lanes-only"))
            embree = 0, high = 0;
        else if (!strcmp(argv[i], "--cpu"))
            g_clock = CLOCK_PROCESS_CPUTIME_ID;
        else if (nsizes < 16 && atof(argv[i]) >= 1)
            sizes[nsizes++] = (size_t)atof(argv[i]);
        else {
            fprintf(stderr, "usage: %s [--runs N] [--mesh sphere|soup|both] "
                            "[--threads-only all|1] [--bins K] [--no-high] [--lanes-only] [--cpu] [sizes...]\n",
                    argv[0]);
            return 2;
        }
    }
    if (runs < 1 || runs > 99) runs = 5;
    if (g_clock != CLOCK_MONOTONIC && !(only && !strcmp(only, "1"))) {
        fprintf(stderr, "--cpu needs --threads-only 1\n");
        return 2;
    }
    if (nsizes == 0) {
        sizes[0] = 100000;
        sizes[1] = 1000000;
        sizes[2] = 3000000;
        nsizes = 3;
    }
    const lanes_cpu_features *cpu = lanes_cpu();
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    printf("CPU: %s, %ld cores; lanes: x86-64 baseline C; Embree %d.%d.%d (its own ISA)\n",
           cpu->brand, cores, RTC_VERSION_MAJOR, RTC_VERSION_MINOR, RTC_VERSION_PATCH);
    printf("medians of %d runs (after one warm-up), %s ms; bins=%d max_leaf=4\n\n", runs,
           g_clock == CLOCK_MONOTONIC ? "wall clock" : "process CPU", bins);
    printf("%-6s %8s %3s | %8s %7s %7s %7s | %8s %8s | %6s %6s %6s\n", "mesh", "tris", "thr",
           "bvh2", "w4", "w8", "w16", "emb-med", "emb-high", "b2/med", "w8/med", "b2/high");
    for (int m = 0; m < 2; m++) {
        const char *name = m == 0 ? "sphere" : "soup";
        if (strcmp(mesh, "both") && strcmp(mesh, name)) continue;
        for (int si = 0; si < nsizes; si++) {
            lanes_scene sc;
            memset(&sc, 0, sizeof sc);
            sc.verts = m == 0 ? make_sphere(sizes[si], &sc.triangle_count)
                              : make_soup(sizes[si], &sc.triangle_count);
            for (int ta = 1; ta >= 0; ta--) {
                if (only && !strcmp(only, "all") && !ta) continue;
                if (only && !strcmp(only, "1") && ta) continue;
                lanes_bvh_build_options o;
                lanes_bvh_default_options(&o);
                o.bins = bins;
                o.threads = ta ? 0 : 1;
                double tb[100], tw[3][100], tm[100], th[100];
                lanes_bvh_stats st2, stw[3];
                /* Interleaved, so that a change in the machine's load between
                 * runs affects both builders alike; the ratios are medians
                 * of per-run ratios. */
                double rb[100], rw[100], rh[100];
                /* One device at a time: Embree limits TBB's threads process
                 * wide (tbb::global_control, the smallest limit wins), so a
                 * threads=1 device alive next to the default one would make
                 * both single-threaded. */
                RTCDevice dev = NULL;
                if (embree) {
                    dev = rtcNewDevice(ta ? NULL : "threads=1");
                    if (!dev) {
                        fprintf(stderr, "embree: no device\n");
                        return 1;
                    }
                }
                for (int r = -1; r < runs; r++) {
                    lanes_bvh2 bvh;
                    lanes_error err;
                    double t0 = now();
                    if (lanes_bvh2_build(&sc, &o, &bvh, &err) != LANES_OK) {
                        fprintf(stderr, "%s\n", err.message);
                        return 1;
                    }
                    double t1 = now();
                    if (r >= 0) tb[r] = t1 - t0;
                    for (int w = 0; w < 3; w++) {
                        lanes_wbvh wb;
                        double a = now();
                        if (lanes_wbvh_build(&sc, 4 << w, &o, &wb, &err) != LANES_OK) {
                            fprintf(stderr, "%s\n", err.message);
                            return 1;
                        }
                        if (r >= 0) tw[w][r] = now() - a;
                        if (r == 0) lanes_wbvh_stats(&wb, 1.0f, 1.0f, &stw[w]);
                        lanes_wbvh_free(&wb);
                    }
                    if (r == 0) lanes_bvh2_stats(&bvh, 1.0f, 1.0f, &st2);
                    lanes_bvh2_free(&bvh);
                    double t = embree ? embree_build(dev, &sc, RTC_BUILD_QUALITY_MEDIUM) : NAN;
                    double h = high ? embree_build(dev, &sc, RTC_BUILD_QUALITY_HIGH) : NAN;
                    if (r >= 0) {
                        tm[r] = t;
                        th[r] = h;
                        rb[r] = tb[r] / t;
                        rw[r] = tw[1][r] / t;
                        rh[r] = tb[r] / h;
                    }
                }
                if (dev) rtcReleaseDevice(dev);
                double mh = high ? median(th, runs) * 1e3 : NAN;
                double mb = median(tb, runs) * 1e3, mm = median(tm, runs) * 1e3;
                double mw[3];
                for (int w = 0; w < 3; w++) mw[w] = median(tw[w], runs) * 1e3;
                printf("%-6s %8zu %3s | %8.1f %7.1f %7.1f %7.1f | %8.1f %8.1f | %6.2f %6.2f %6.2f\n",
                       name, sc.triangle_count, ta ? "all" : "1", mb, mw[0], mw[1], mw[2], mm, mh,
                       embree ? median(rb, runs) : NAN, embree ? median(rw, runs) : NAN,
                       high ? median(rh, runs) : NAN);
                if (ta || (only && !strcmp(only, "1")))
                    printf("       bvh2: %zu nodes, %zu leaves, avg leaf %.2f, depth %d, SAH %.2f, "
                           "%.1f MB | w4 %zu nodes SAH %.2f | w8 %zu SAH %.2f | w16 %zu SAH %.2f (leaves by block)\n",
                           st2.nodes, st2.leaves, st2.avg_leaf_size, st2.depth, st2.sah_cost,
                           st2.bytes / 1e6, stw[0].nodes, stw[0].sah_cost, stw[1].nodes,
                           stw[1].sah_cost, stw[2].nodes, stw[2].sah_cost);
                fflush(stdout);
            }
            free(sc.verts);
        }
    }
    return 0;
}
