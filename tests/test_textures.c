/* The solid procedural textures (trace/kernels/texture_core.h) at every
 * kernel set the CPU runs, against the double reference of
 * texture_reference.c:
 *   - the noise within 1e-5 of the reference, 0 on the lattice, inside
 *     [-1, 1], continuous across cell faces;
 *   - checker exactly (away from cell faces, where float and double may
 *     pick different cells), noise, marble and wood weights within a
 *     stated tolerance, every weight in [0, 1] and every color between
 *     color_a and color_b.
 *
 *   test_textures [--isa a,b,...] */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "simd/isa.h"
#include "trace/kernels.h"
#include "texture_reference.h"

typedef void (*noise_fn)(size_t, const float *, float *);
typedef void (*texture_fn)(const lanes_texture *, size_t, const float *, float *, float *);

enum { N = 1 << 14 };

/* The weights' stated accuracy against the reference, for points within
 * 100 pattern sizes of the origin (marble's phase grows with x, and its
 * float rounding with it). Wood's weight wraps from 1 to 0 at each ring,
 * so it is compared around the circle. */
#define NOISE_TOL 1e-5
#define WEIGHT_TOL 1e-4

static const char *const kind_names[] = {"checker", "noise", "marble", "wood"};

/* points in SoA form, as the kernels take them */
static float p[3 * N], out[N], color[3 * N];
static float *const x = p, *const y = p + N, *const z = p + 2 * N;

static float coordinate(harness_rng *r, double range) { return (float)((2.0 * harness_uniform(r) - 1.0) * range); }

static void test_noise(const char *isa, noise_fn noise, harness_rng *r)
{
    double worst = 0.0;
    for (int round = 0; round < 16; round++) {
        double range = round < 8 ? 4.0 : 1000.0;
        for (size_t i = 0; i < N; i++) x[i] = coordinate(r, range), y[i] = coordinate(r, range), z[i] = coordinate(r, range);
        noise(N, p, out);
        for (size_t i = 0; i < N; i++) {
            double want = ref_noise(x[i], y[i], z[i]);
            worst = fmax(worst, fabs(out[i] - want));
            CHECK(fabs(out[i] - want) <= NOISE_TOL && fabs(out[i]) <= 1.0f, "%s noise(%a, %a, %a) = %.7f, reference %.7f",
                  isa, (double)x[i], (double)y[i], (double)z[i], (double)out[i], want);
        }
    }
    /* 0 on the lattice; the same value on both sides of a cell face */
    for (size_t i = 0; i < N; i++) {
        x[i] = (float)((int)(harness_next(r) % 200) - 100), y[i] = (float)((int)(harness_next(r) % 200) - 100);
        z[i] = (float)((int)(harness_next(r) % 200) - 100);
    }
    noise(N, p, out);
    for (size_t i = 0; i < N; i++)
        CHECK(out[i] == 0.0f, "%s noise at the lattice point (%g, %g, %g) = %g", isa, (double)x[i], (double)y[i],
              (double)z[i], (double)out[i]);
    static float below[N];
    for (size_t i = 0; i < N; i++) y[i] += 0.37f, z[i] += 0.61f;
    noise(N, p, out);
    for (size_t i = 0; i < N; i++) x[i] = nextafterf(x[i], -INFINITY);
    noise(N, p, below);
    for (size_t i = 0; i < N; i++)
        CHECK(fabsf(out[i] - below[i]) <= 1e-5f, "%s noise jumps across the face x = %g: %g against %g", isa,
              (double)x[i], (double)out[i], (double)below[i]);
    printf("  %s noise: worst difference from the reference %.2g (stated %.0e)\n", isa, worst, NOISE_TOL);
}

static void test_texture(const char *isa, texture_fn texture, harness_rng *r)
{
    for (int kind = LANES_TEXTURE_CHECKER; kind <= LANES_TEXTURE_WOOD; kind++) {
        double worst = 0.0;
        long compared = 0;
        for (int rep = 0; rep < 8; rep++) {
            lanes_texture t = {.kind = (lanes_texture_kind)kind, .scale = (float)(0.05 + 3.0 * harness_uniform(r))};
            for (int k = 0; k < 3; k++)
                t.color_a[k] = (float)harness_uniform(r), t.color_b[k] = (float)harness_uniform(r);
            for (size_t i = 0; i < N; i++) {
                double range = 100.0 * t.scale;
                x[i] = coordinate(r, range), y[i] = coordinate(r, range), z[i] = coordinate(r, range);
            }
            texture(&t, N, p, out, color);
            const float k = 1.0f / t.scale;
            for (size_t i = 0; i < N; i++) {
                /* the point as the set scales it, then in double */
                double px = x[i] * k, py = y[i] * k, pz = z[i] * k;
                double w = out[i];
                CHECK(w >= 0.0 && w <= 1.0, "%s %s: weight %g outside [0, 1]", isa, kind_names[kind], w);
                for (int c = 0; c < 3; c++) {
                    double lo = fmin(t.color_a[c], t.color_b[c]), hi = fmax(t.color_a[c], t.color_b[c]);
                    double got = color[(size_t)c * N + i];
                    CHECK(got >= lo - 1e-6 && got <= hi + 1e-6, "%s %s: color %g outside [%g, %g]", isa,
                          kind_names[kind], got, lo, hi);
                }
                if (kind == LANES_TEXTURE_CHECKER) {
                    double m = fmin(fmin(fabs(px - round(px)), fabs(py - round(py))), fabs(pz - round(pz)));
                    if (m < 1e-4) continue;
                }
                double want = ref_texture_weight((lanes_texture_kind)kind, px, py, pz), d = fabs(w - want);
                if (kind == LANES_TEXTURE_WOOD) d = fmin(d, 1.0 - d);
                compared++;
                worst = fmax(worst, d);
                CHECK(d <= (kind == LANES_TEXTURE_CHECKER ? 0.0 : WEIGHT_TOL), "%s %s (scale %g) at (%a, %a, %a): weight %.7f, reference %.7f",
                      isa, kind_names[kind], (double)t.scale, (double)x[i], (double)y[i], (double)z[i], w, want);
            }
        }
        CHECK(compared > 8 * N / 2, "%s %s: only %ld points compared", isa, kind_names[kind], compared);
        printf("  %s %s: worst difference from the reference %.2g\n", isa, kind_names[kind], worst);
    }
}

int main(int argc, char **argv)
{
    const char *isa_list = NULL;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--isa") == 0 && i + 1 < argc) {
            isa_list = argv[++i];
        } else {
            fprintf(stderr, "usage: %s [--isa a,b,...]\n  sets: %s\n", argv[0], lanes_isa_all_names());
            return 2;
        }
    }
    printf("test_textures: CPU %s\n", lanes_cpu()->brand);
    for (int i = 0; i < LANES_ISA_COUNT; i++) {
        lanes_isa isa = (lanes_isa)i;
        const char *name = lanes_isa_name(isa);
        if (!harness_in_list(isa_list, name) || !lanes_isa_compiled(isa)) continue;
        if (!lanes_isa_cpu_can_run(isa)) {
            printf("SKIP %s: this CPU cannot run it\n", name);
            harness_skip();
            continue;
        }
        harness_rng r = harness_rng_seed(0x7e57u);
        const lanes_kernels *k = lanes_kernels_for(isa);
        test_noise(name, k->noise, &r);
        test_texture(name, k->texture_color, &r);
    }
    return harness_summary("test_textures");
}
