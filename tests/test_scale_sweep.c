/* Every accuracy mode at every scale: correct, or refused (issue 14, part 1).
 *
 * 1. Scale: a scene of a diffuse sphere, a floor, a mirror box and a point
 *    light (all of it, camera and light intensity included, scaled by s =
 *    10^k, k = -17..17) renders in each mode, with the scalar set and the
 *    best set this CPU runs, to the image of the unit-scale scene, or the
 *    render refuses it (LANES_ERR_BAD_INPUT, the limits of
 *    trace/scene_plan.h). Refusing is allowed only outside the range the
 *    documentation promises: fast and default modes must render k = -10..11,
 *    robust mode k = -15..16. Before, the fixed 1e-6 term of the scene
 *    epsilon displaced shadows at k = -6 and blackened everything by -7, and
 *    Möller-Trumbore lost the floor at k = 13, all without a word.
 * 2. Position: the same unit scene translated by T on every axis. Where the
 *    scene plan says fast and default modes are safe (no robust
 *    recommendation), the default-mode image must match the robust one;
 *    the translation where default mode first differs is printed, with the
 *    plan's verdict, so the margin of the verdict can be read.
 *
 * Images are compared through OpenImageIO (PNG, 8-bit): a match has at most
 * MAX_FRACTION_OVER of its pixels off by more than THRESHOLD. Scaling moves
 * every hit point by a few ulps relative to the unit scene, which flips the
 * odd pixel on an edge or a shadow's boundary; a wrong scale (lost shadows,
 * black surfaces, acne) changes thousands of the 4096.
 *
 *   test_scale_sweep OUTDIR */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench/image_io.h"
#include "build/scene.h"
#include "build/scene_file.h"
#include "simd/isa.h"
#include "trace/kernels.h"
#include "trace/render.h"
#include "trace/scene_plan.h"
#include "tests/harness.h"

#define SIZE 64
#define THRESHOLD 0.02
#define MAX_FRACTION_OVER 0.005
#define K_MIN (-17)
#define K_MAX 17

/* The scene at scale s, moved by t on every axis. */
static bool make_scene(double s, double t, lanes_scene *out)
{
    char text[2048];
    int n = snprintf(text, sizeof text,
                     "{\"materials\": {\"m\": {\"type\": \"diffuse\", \"color\": 0.7},"
                     " \"mirror\": {\"type\": \"mirror\", \"color\": 0.9}},"
                     " \"objects\": ["
                     "{\"builtin\": \"sphere\", \"material\": \"m\", \"scale\": %.17g,"
                     " \"translate\": [%.17g, %.17g, %.17g]},"
                     "{\"builtin\": \"plane\", \"material\": \"m\", \"scale\": %.17g,"
                     " \"translate\": [%.17g, %.17g, %.17g]},"
                     "{\"builtin\": \"box\", \"material\": \"mirror\", \"scale\": %.17g, \"rotate\": [0, 30, 0],"
                     " \"translate\": [%.17g, %.17g, %.17g]}],"
                     " \"lights\": [{\"type\": \"point\", \"position\": [%.17g, %.17g, %.17g],"
                     " \"intensity\": %.17g}],"
                     " \"camera\": {\"eye\": [%.17g, %.17g, %.17g], \"target\": [%.17g, %.17g, %.17g],"
                     " \"fov\": 40}}",
                     s, t, s + t, t, 4 * s, t, t, t, 0.5 * s, -1.4 * s + t, 0.5 * s + t, s + t, 2 * s + t,
                     4 * s + t, 3 * s + t, 30 * s * s, t, 2 * s + t, 6 * s + t, t, s + t, t);
    lanes_error err;
    if (n < 0 || (size_t)n >= sizeof text) {
        harness_fail("scene text too long");
        return false;
    }
    if (lanes_scene_file_parse(text, (size_t)n, "sweep", NULL, out, &err) != LANES_OK) {
        harness_fail("scene at scale %g, translation %g: %s", s, t, err.message);
        return false;
    }
    return true;
}

typedef enum { RENDERED, REFUSED, FAILED } outcome;

static outcome render_to(const lanes_scene *scene, lanes_isa isa, lanes_accuracy mode, const char *path,
                         char *why, size_t why_size)
{
    lanes_error err;
    memset(&err, 0, sizeof err);
    lanes_render_accel accel;
    if (lanes_render_accel_build(scene, lanes_kernels_for(isa), false, 1, &accel, &err) != LANES_OK) {
        harness_fail("accel at %s: %s", lanes_isa_name(isa), err.message);
        return FAILED;
    }
    lanes_render_options o;
    lanes_render_default_options(&o);
    o.isa = isa;
    o.scheme = LANES_SCHEME_WIDE;
    o.accuracy = mode;
    o.width = o.height = SIZE;
    o.threads = 1;
    lanes_render_result r;
    lanes_status st = lanes_render(scene, &accel, &o, &r, &err);
    lanes_render_accel_free(&accel);
    if (st == LANES_ERR_BAD_INPUT) {
        snprintf(why, why_size, "%s", err.message);
        return REFUSED;
    }
    if (st != LANES_OK) {
        harness_fail("render at %s, %s: %s", lanes_isa_name(isa), lanes_accuracy_name(mode), err.message);
        return FAILED;
    }
    st = lanes_image_write(path, r.width, r.height, r.rgb, &err);
    lanes_render_result_free(&r);
    if (st != LANES_OK) {
        harness_fail("writing %s: %s", path, err.message);
        return FAILED;
    }
    return RENDERED;
}

/* Whether two written images match; *over receives the pixels off. */
static bool images_match(const char *a, const char *b, long long *over)
{
    lanes_image_diff d;
    lanes_error err;
    if (lanes_image_compare(a, b, THRESHOLD, &d, &err) != LANES_OK) {
        harness_fail("comparing %s and %s: %s", a, b, err.message);
        *over = -1;
        return false;
    }
    *over = d.pixels_over;
    return (double)d.pixels_over <= MAX_FRACTION_OVER * (double)d.pixels;
}

static void scale_sweep(const char *dir, lanes_isa isa)
{
    for (int mode = 0; mode < LANES_ACCURACY_COUNT; mode++) {
        const char *mname = lanes_accuracy_name((lanes_accuracy)mode);
        int promise_lo = mode == LANES_ACCURACY_ROBUST ? -15 : -10;
        int promise_hi = mode == LANES_ACCURACY_ROBUST ? 16 : 11;
        char ref[1024], why[512];
        snprintf(ref, sizeof ref, "%s/scale_%s_%s_ref.png", dir, mname, lanes_isa_name(isa));
        lanes_scene unit;
        if (!make_scene(1.0, 0.0, &unit)) return;
        outcome o = render_to(&unit, isa, (lanes_accuracy)mode, ref, why, sizeof why);
        lanes_scene_free(&unit);
        CHECK(o == RENDERED, "%s %s: the unit scene renders", lanes_isa_name(isa), mname);
        if (o != RENDERED) continue;
        printf("%-7s %-7s", lanes_isa_name(isa), mname);
        for (int k = K_MIN; k <= K_MAX; k++) {
            lanes_scene scene;
            if (!make_scene(pow(10.0, k), 0.0, &scene)) continue;
            char path[1024];
            snprintf(path, sizeof path, "%s/scale_%s_%s_%d.png", dir, mname, lanes_isa_name(isa), k);
            o = render_to(&scene, isa, (lanes_accuracy)mode, path, why, sizeof why);
            lanes_scene_free(&scene);
            bool promised = k >= promise_lo && k <= promise_hi;
            if (o == REFUSED) {
                printf(" %d:refused", k);
                CHECK(!promised, "%s %s at 1e%d: refused inside the promised range: %s", lanes_isa_name(isa),
                      mname, k, why);
                CHECK(strstr(why, "diagonal") || strstr(why, "too large") || strstr(why, "spans"),
                      "%s %s at 1e%d: the refusal names the size: %s", lanes_isa_name(isa), mname, k, why);
                continue;
            }
            if (o != RENDERED) continue;
            long long over;
            bool same = images_match(ref, path, &over);
            printf(" %d:%s", k, same ? "ok" : "WRONG");
            CHECK(same, "%s %s at 1e%d: %lld of %d pixels differ from the unit-scale image by over %g",
                  lanes_isa_name(isa), mname, k, over, SIZE * SIZE, THRESHOLD);
        }
        printf("\n");
    }
}

static void position_sweep(const char *dir, lanes_isa isa)
{
    static const double shifts[] = {0, 10, 30, 100, 300, 1e3, 3e3, 1e4, 1e5, 1e6};
    int safe_cases = 0;
    for (size_t i = 0; i < sizeof shifts / sizeof shifts[0]; i++) {
        lanes_scene scene;
        if (!make_scene(1.0, shifts[i], &scene)) continue;
        lanes_scene_plan plan;
        lanes_scene_plan_make(&scene, LANES_ACCURACY_DEFAULT, &plan);
        char pd[1024], pr[1024], why[512];
        snprintf(pd, sizeof pd, "%s/shift_default_%s_%zu.png", dir, lanes_isa_name(isa), i);
        snprintf(pr, sizeof pr, "%s/shift_robust_%s_%zu.png", dir, lanes_isa_name(isa), i);
        outcome od = render_to(&scene, isa, LANES_ACCURACY_DEFAULT, pd, why, sizeof why);
        outcome orb = render_to(&scene, isa, LANES_ACCURACY_ROBUST, pr, why, sizeof why);
        lanes_scene_free(&scene);
        CHECK(od == RENDERED && orb == RENDERED, "%s: a unit scene moved by %g renders", lanes_isa_name(isa),
              shifts[i]);
        if (od != RENDERED || orb != RENDERED) continue;
        long long over;
        bool same = images_match(pr, pd, &over);
        bool safe = !plan.recommend_robust;
        printf("%-7s moved by %-8g (%.1f diagonals): plan says %-6s offset %.3g, bound %.3g; default %s robust "
               "(%lld pixels off)\n",
               lanes_isa_name(isa), shifts[i], shifts[i] / plan.diagonal, safe ? "safe," : "robust,", plan.epsilon,
               plan.offset_bound, same ? "matches" : "differs from", over);
        if (safe) {
            safe_cases++;
            CHECK(same, "%s moved by %g: the plan calls default mode safe, but its image differs from robust "
                        "mode's on %lld pixels",
                  lanes_isa_name(isa), shifts[i], over);
        }
    }
    /* the verdict must not be "never safe", which would pass vacuously */
    CHECK(safe_cases >= 2, "%s: the plan calls default mode safe at the origin and nearby (%d cases)",
          lanes_isa_name(isa), safe_cases);
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: test_scale_sweep OUTDIR\n");
        return 2;
    }
    lanes_isa sets[2] = {LANES_ISA_SCALAR, lanes_isa_best()};
    int nsets = sets[1] == LANES_ISA_SCALAR ? 1 : 2;
    for (int i = 0; i < nsets; i++) {
        printf("scale sweep, %s (k: scene scaled by 10^k)\n", lanes_isa_name(sets[i]));
        scale_sweep(argv[1], sets[i]);
        position_sweep(argv[1], sets[i]);
    }
    return harness_summary("test_scale_sweep");
}
