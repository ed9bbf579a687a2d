/* What sharing the caller's arrays costs: lanes_accel_create_shared against
 * lanes_accel_create on the same indexed mesh and the same rays, through
 * the public API only.
 *
 *   bench_shared_geometry [--isa NAME] [--runs N] [--triangles N] [--rays N]
 *
 * The mesh is a bumpy UV sphere of about N triangles (default 1,000,000),
 * vertices shared between triangles as in a scanned model. Two ray sets:
 * primary rays from a camera outside (coherent, traced as a stream and as
 * packets) and rays from random points inside in random directions
 * (incoherent: every one hits), traced for the closest hit and for
 * occlusion. Each query runs on both accels in turn (copied, shared,
 * copied, ...) N times (default 7) after one warm-up; the figures are
 * medians, in million rays per second on one thread, and the median of the
 * per-run ratios shared / copied. Every run also checks that both accels
 * return the same hits. */
#define _POSIX_C_SOURCE 200809L

#include <lanes/lanes.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define PI 3.14159265358979323846

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static unsigned long long rng = 0x243f6a8885a308d3ull;
static double uniform(void) /* [0, 1) */
{
    rng ^= rng << 13, rng ^= rng >> 7, rng ^= rng << 17;
    return (double)(rng >> 11) * 0x1.0p-53;
}

typedef struct mesh {
    float *v;
    uint32_t *idx;
    size_t nv, nt;
} mesh;

static mesh make_sphere(size_t n)
{
    size_t slices = (size_t)sqrt((double)n), stacks = n / (2 * slices);
    if (slices < 3) slices = 3;
    if (stacks < 2) stacks = 2;
    mesh m = {malloc((stacks + 1) * slices * 3 * sizeof(float)), malloc(stacks * slices * 6 * sizeof(uint32_t)),
              (stacks + 1) * slices, 0};
    if (!m.v || !m.idx) exit(2);
    for (size_t i = 0; i <= stacks; i++)
        for (size_t j = 0; j < slices; j++) {
            double th = PI * (double)i / (double)stacks, ph = 2 * PI * (double)j / (double)slices;
            double r = 1.0 + 0.03 * (uniform() - 0.5);
            float *p = m.v + 3 * (i * slices + j);
            p[0] = (float)(r * sin(th) * cos(ph)), p[1] = (float)(r * cos(th)), p[2] = (float)(r * sin(th) * sin(ph));
        }
    for (size_t i = 0; i < stacks; i++)
        for (size_t j = 0; j < slices; j++) {
            uint32_t a = (uint32_t)(i * slices + j), b = (uint32_t)(i * slices + (j + 1) % slices);
            uint32_t c = a + (uint32_t)slices, d = b + (uint32_t)slices;
            uint32_t q[6] = {a, c, b, b, c, d};
            memcpy(m.idx + 3 * m.nt, q, sizeof q);
            m.nt += 2;
        }
    return m;
}

typedef struct rays {
    float *a[8]; /* ox oy oz dx dy dz tnear tfar */
    size_t n;
} rays;

static lanes_rays_soa soa_of(const rays *r)
{
    lanes_rays_soa s = {r->a[0], r->a[1], r->a[2], r->a[3], r->a[4], r->a[5], r->a[6], r->a[7]};
    return s;
}

/* Primary rays of a square image in 8x8 tiles, or random rays from inside. */
static rays make_rays(size_t n, bool primary)
{
    rays r = {{0}, n};
    for (int k = 0; k < 8; k++)
        if (!(r.a[k] = malloc(n * sizeof(float)))) exit(2);
    size_t side = (size_t)sqrt((double)n);
    for (size_t i = 0; i < n; i++) {
        float o[3], d[3];
        if (primary) {
            size_t tile = i / 64, in = i % 64, tiles = side / 8 ? side / 8 : 1;
            double px = (double)(tile % tiles * 8 + in % 8) / (double)side - 0.5;
            double py = (double)(tile / tiles * 8 + in / 8) / (double)side - 0.5;
            o[0] = 0, o[1] = 0, o[2] = -3;
            d[0] = (float)(px * 0.8), d[1] = (float)(py * 0.8), d[2] = 1;
        } else {
            for (int k = 0; k < 3; k++) o[k] = (float)(uniform() - 0.5), d[k] = (float)(2 * uniform() - 1);
            if (d[0] == 0 && d[1] == 0 && d[2] == 0) d[2] = 1;
        }
        for (int k = 0; k < 3; k++) r.a[k][i] = o[k], r.a[3 + k][i] = d[k];
        r.a[6][i] = 0, r.a[7][i] = INFINITY;
    }
    return r;
}

typedef enum query { CLOSEST_STREAM, CLOSEST_PACKET, OCCLUDED_STREAM } query;

static double run(lanes_accel a, query q, const rays *r, lanes_hits_soa *h, uint8_t *occ)
{
    lanes_rays_soa s = soa_of(r);
    double t0 = now();
    lanes_status st = q == CLOSEST_STREAM   ? lanes_intersect_stream(a, &s, r->n, h)
                      : q == CLOSEST_PACKET ? lanes_intersect_packet(a, &s, r->n, h)
                                            : lanes_occluded_stream(a, &s, r->n, occ);
    double t = now() - t0;
    if (st != LANES_OK) {
        fprintf(stderr, "bench_shared_geometry: %s\n", lanes_last_error_message());
        exit(1);
    }
    return t;
}

static int by_value(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median(double *x, int n)
{
    qsort(x, (size_t)n, sizeof *x, by_value);
    return n % 2 ? x[n / 2] : 0.5 * (x[n / 2 - 1] + x[n / 2]);
}

static void cpu_name(char *out, size_t size)
{
    snprintf(out, size, "unknown CPU");
    FILE *f = fopen("/proc/cpuinfo", "r");
    char line[256];
    while (f && fgets(line, sizeof line, f))
        if (strncmp(line, "model name", 10) == 0 && strchr(line, ':')) {
            snprintf(out, size, "%s", strchr(line, ':') + 2);
            out[strcspn(out, "\n")] = 0;
            break;
        }
    if (f) fclose(f);
}

int main(int argc, char **argv)
{
    const char *isa = NULL;
    int runs = 7;
    size_t triangles = 1000000, nrays = 1 << 18;
    for (int i = 1; i < argc; i++) {
        const char *next = i + 1 < argc ? argv[i + 1] : NULL;
        if (strcmp(argv[i], "--isa") == 0 && next) isa = argv[++i];
        else if (strcmp(argv[i], "--runs") == 0 && next) runs = atoi(argv[++i]);
        else if (strcmp(argv[i], "--triangles") == 0 && next) triangles = strtoull(argv[++i], NULL, 10);
        else if (strcmp(argv[i], "--rays") == 0 && next) nrays = strtoull(argv[++i], NULL, 10);
        else {
            fprintf(stderr, "usage: bench_shared_geometry [--isa NAME] [--runs N] [--triangles N] [--rays N]\n");
            return 2;
        }
    }
    if (runs < 1 || runs > 1000 || triangles < 8 || triangles > 100000000 || nrays < 64 || nrays > 100000000) {
        fprintf(stderr, "bench_shared_geometry: --runs 1..1000, --triangles 8..1e8, --rays 64..1e8\n");
        return 2;
    }
    char config[64];
    snprintf(config, sizeof config, "threads=1%s%s", isa ? ",isa=" : "", isa ? isa : "");
    lanes_device d;
    if (lanes_device_create(config, &d) != LANES_OK) {
        fprintf(stderr, "bench_shared_geometry: %s\n", lanes_last_error_message());
        return 2;
    }
    lanes_device_info di;
    lanes_device_get_info(d, &di);
    mesh m = make_sphere(triangles);
    lanes_accel acc[2];
    lanes_accel_info ai[2];
    if (lanes_accel_create(d, m.v, m.nv, m.idx, m.nt, &acc[0]) != LANES_OK ||
        lanes_accel_create_shared(d, m.v, m.nv, m.idx, m.nt, &acc[1]) != LANES_OK) {
        fprintf(stderr, "bench_shared_geometry: %s\n", lanes_last_error_message());
        return 2;
    }
    for (int k = 0; k < 2; k++) lanes_accel_get_info(acc[k], &ai[k]);
    char cpu[128];
    cpu_name(cpu, sizeof cpu);
    printf("liblanes %s, %s, set %s (%d lanes, node width %d), one thread\n", lanes_version(), cpu, di.isa,
           di.lanes, di.node_width);
    printf("mesh: %zu triangles, %zu vertices; accel bytes: copied %.1f MB, shared %.1f MB "
           "(+ the caller's arrays, %.1f MB)\n",
           m.nt, m.nv, ai[0].bytes / 1e6, ai[1].bytes / 1e6,
           (double)(m.nv * 3 * sizeof(float) + m.nt * 3 * sizeof(uint32_t)) / 1e6);
    printf("%zu rays per set, %d runs after a warm-up, medians\n\n", nrays, runs);
    printf("%-10s %-16s %10s %10s %14s\n", "rays", "query", "copied", "shared", "shared/copied");
    printf("%-10s %-16s %10s %10s %14s\n", "", "", "Mrays/s", "Mrays/s", "time ratio");

    rays sets[2] = {make_rays(nrays, true), make_rays(nrays, false)};
    const char *set_names[2] = {"primary", "incoherent"};
    const query queries[3] = {CLOSEST_STREAM, CLOSEST_PACKET, OCCLUDED_STREAM};
    const char *query_names[3] = {"closest stream", "closest packet", "occluded stream"};
    float *out[2][4];
    uint8_t *occ[2];
    for (int k = 0; k < 2; k++) {
        for (int f = 0; f < 4; f++)
            if (!(out[k][f] = malloc(nrays * sizeof(float)))) return 2;
        if (!(occ[k] = malloc(nrays))) return 2;
    }
    double *time[2] = {malloc((size_t)runs * sizeof(double)), malloc((size_t)runs * sizeof(double))};
    double *ratio = malloc((size_t)runs * sizeof(double));
    size_t mismatches = 0;
    for (int s = 0; s < 2; s++)
        for (int q = 0; q < 3; q++) {
            if (s == 1 && queries[q] == CLOSEST_PACKET) continue; /* packets are for coherent rays */
            for (int r = -1; r < runs; r++) {
                double t[2];
                for (int k = 0; k < 2; k++) {
                    lanes_hits_soa h = {out[k][0], out[k][1], out[k][2], (uint32_t *)(void *)out[k][3]};
                    t[k] = run(acc[k], queries[q], &sets[s], &h, occ[k]);
                }
                if (r < 0) continue;
                time[0][r] = t[0], time[1][r] = t[1], ratio[r] = t[1] / t[0];
                bool same = queries[q] == OCCLUDED_STREAM
                                ? memcmp(occ[0], occ[1], nrays) == 0
                                : memcmp(out[0][0], out[1][0], nrays * sizeof(float)) == 0 &&
                                      memcmp(out[0][3], out[1][3], nrays * sizeof(float)) == 0;
                mismatches += !same;
            }
            double rc = median(time[0], runs), rs = median(time[1], runs);
            printf("%-10s %-16s %10.2f %10.2f %14.3f\n", set_names[s], query_names[q], (double)nrays / rc / 1e6,
                   (double)nrays / rs / 1e6, median(ratio, runs));
        }
    if (mismatches) printf("\nFAIL: the shared accel's hits differed from the copied one's in %zu runs\n", mismatches);
    for (int k = 0; k < 2; k++) {
        for (int f = 0; f < 4; f++) free(out[k][f]);
        free(occ[k]);
        lanes_accel_release(acc[k]);
        for (int f = 0; f < 8; f++) free(sets[k].a[f]);
    }
    free(time[0]), free(time[1]), free(ratio);
    lanes_device_release(d);
    free(m.v), free(m.idx);
    return mismatches ? 1 : 0;
}
