/* The same image from two kernel sets: a scene (the default one unless
 * --scene names another) rendered in one accuracy mode (--accuracy, default
 * unless told) with the scalar set and with the best one this CPU runs (wide
 * scheme both), written
 * as PNG through OpenImageIO and compared with its compare (idiff's engine).
 *
 * Two sets may legitimately differ in two ways only:
 *  - FMA rounding (scalar, sse4 and avx have none; avx2 and avx512 fuse),
 *    which moves hit points by an ulp and, through the glass sphere's
 *    chains of refractions, can send a few rays elsewhere;
 *  - ties: where two triangles are hit at exactly the same t, the BVH of
 *    the set's width decides which one is reported. The default camera
 *    looks squarely into the room, so pixel centres on the image diagonals
 *    hit the room's corner edges, where walls of different colours meet.
 * Both touch isolated pixels, so the images must agree to 1/255 everywhere
 * but on at most 0.1% of the pixels, with a mean error below 1e-3. And two
 * sets that compute the same arithmetic on the same BVH width (scalar and
 * sse4: no FMA, 4-wide nodes) must give the same image bit for bit.
 *
 *   test_render_isa OUTDIR [--size N] [--scene SPEC] [--accuracy MODE] [ISA_A ISA_B]
 */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench/image_io.h"
#include "build/bvh.h"
#include "build/scene.h"
#include "build/scene_load.h"
#include "simd/isa.h"
#include "trace/kernels.h"
#include "trace/render.h"

/* 8-bit images: one step is 1/255. Over that, a pixel really differs. */
#define THRESHOLD (1.0 / 255.0 + 1e-6)
#define MAX_FRACTION_OVER 1e-3
#define MAX_MEAN_ERROR 1e-3

static lanes_accuracy accuracy = LANES_ACCURACY_DEFAULT;

/* The options both renders use: the wide scheme, the mode asked for, size x size. */
static lanes_render_options wide_options(lanes_isa isa, int size)
{
    lanes_render_options opt;
    lanes_render_default_options(&opt);
    opt.isa = isa;
    opt.scheme = LANES_SCHEME_WIDE;
    opt.accuracy = accuracy;
    opt.width = opt.height = size;
    return opt;
}

static bool render_with(const lanes_scene *scene, lanes_isa isa, int size, const char *path,
                        lanes_render_result *res)
{
    lanes_error err;
    memset(&err, 0, sizeof err);
    const lanes_kernels *k = lanes_kernels_for(isa);
    lanes_render_accel accel;
    if (lanes_render_accel_build(scene, k, false, 0, &accel, &err) != LANES_OK) {
        printf("FAIL: acceleration structure for %s: %s\n", k->name, err.message);
        return false;
    }
    lanes_render_options opt = wide_options(isa, size);
    bool ok = lanes_render(scene, &accel, &opt, res, &err) == LANES_OK;
    lanes_render_accel_free(&accel);
    if (!ok) {
        printf("FAIL: render with %s: %s\n", k->name, err.message);
        return false;
    }
    if (lanes_image_write(path, res->width, res->height, res->rgb, &err) != LANES_OK) {
        printf("FAIL: writing %s: %s\n", path, err.message);
        return false;
    }
    printf("%-10s %dx%d, %llu rays in %.3f s -> %s\n", k->name, res->width, res->height,
           (unsigned long long)res->rays, res->seconds, path);
    return true;
}

int main(int argc, char **argv)
{
    setvbuf(stdout, NULL, _IOLBF, 0);
    if (argc < 2) {
        printf("usage: test_render_isa OUTDIR [--size N] [--scene SPEC] [--accuracy MODE] [ISA_A ISA_B]\n");
        return 2;
    }
    const char *dir = argv[1];
    int size = 256;
    lanes_isa a = LANES_ISA_SCALAR, b = lanes_isa_best();
    int i = 2;
    const char *spec = "default";
    bool bad_mode = false;
    for (;;) {
        if (i + 1 < argc && strcmp(argv[i], "--size") == 0) {
            size = atoi(argv[i + 1]), i += 2;
        } else if (i + 1 < argc && strcmp(argv[i], "--scene") == 0) {
            spec = argv[i + 1], i += 2;
        } else if (i + 1 < argc && strcmp(argv[i], "--accuracy") == 0) {
            int mode = lanes_accuracy_from_name(argv[i + 1]);
            bad_mode = mode < 0;
            accuracy = bad_mode ? accuracy : (lanes_accuracy)mode;
            i += 2;
        } else {
            break;
        }
    }
    bool explicit_pair = i + 1 < argc;
    if (explicit_pair) a = lanes_isa_from_name(argv[i]), b = lanes_isa_from_name(argv[i + 1]);
    if (size < 8 || size > 4096 || bad_mode || a == LANES_ISA_NONE || b == LANES_ISA_NONE) {
        printf("bad arguments\n");
        return 2;
    }
    if (!lanes_isa_supported(a) || !lanes_isa_supported(b)) {
        printf("SKIP: %s or %s is not supported here\n", lanes_isa_name(a), lanes_isa_name(b));
        return 77;
    }
    printf("cpu: %s\n", lanes_cpu()->brand);

    lanes_scene scene;
    lanes_error err;
    memset(&err, 0, sizeof err);
    lanes_scene_init(&scene);
    if (lanes_scene_load(spec, &scene, &err) != LANES_OK) {
        printf("FAIL: scene %s: %s\n", spec, err.message);
        return 1;
    }
    char pa[1024], pb[1024];
    /* the mode in the name: tests of two modes may run at once */
    snprintf(pa, sizeof pa, "%s/render_%s_%s.png", dir, lanes_accuracy_name(accuracy), lanes_isa_name(a));
    snprintf(pb, sizeof pb, "%s/render_%s_%s.png", dir, lanes_accuracy_name(accuracy), lanes_isa_name(b));
    lanes_render_result ra, rb;
    if (!render_with(&scene, a, size, pa, &ra) || !render_with(&scene, b, size, pb, &rb)) return 1;
    int status = 0;

    /* the float images first: where and how much they differ, before 8-bit
     * quantisation hides it */
    double fmax_err = 0.0;
    long differ = 0;
    size_t n = (size_t)ra.width * (size_t)ra.height;
    for (size_t p = 0; p < n; p++) {
        double e = 0.0;
        for (int c = 0; c < 3; c++) e = fmax(e, fabs((double)ra.rgb[3 * p + c] - rb.rgb[3 * p + c]));
        if (e > 0) differ++;
        fmax_err = fmax(fmax_err, e);
    }
    printf("float images: %ld of %zu pixels differ, max error %.3g (linear)\n", differ, n, fmax_err);
    if (ra.rays != rb.rays)
        printf("note: ray counts differ (%llu vs %llu): some shadow or secondary ray changed\n",
               (unsigned long long)ra.rays, (unsigned long long)rb.rays);

    lanes_image_diff d;
    if (lanes_image_compare(pa, pb, THRESHOLD, &d, &err) != LANES_OK) {
        printf("FAIL: comparing: %s\n", err.message);
        return 1;
    }
    long long allowed = (long long)(MAX_FRACTION_OVER * (double)d.pixels);
    bool pass = d.pixels_over <= allowed && d.mean_error < MAX_MEAN_ERROR;
    printf("PNG compare (OpenImageIO) %s vs %s: mean error %.3g, max error %.3g, %lld of %lld "
           "pixels over %.4f (allowed %lld, mean below %.0e) -> %s\n",
           lanes_isa_name(a), lanes_isa_name(b), d.mean_error, d.max_error, d.pixels_over, d.pixels,
           THRESHOLD, allowed, MAX_MEAN_ERROR, pass ? "ok" : "FAIL");
    if (!pass) status = 1;

    /* same arithmetic, same BVH: the same image, bit for bit */
    if (!explicit_pair && lanes_isa_supported(LANES_ISA_SSE4) && b != LANES_ISA_SSE4) {
        char pc[1024];
        lanes_render_result rc;
        snprintf(pc, sizeof pc, "%s/render_%s_sse4.png", dir, lanes_accuracy_name(accuracy));
        if (!render_with(&scene, LANES_ISA_SSE4, size, pc, &rc)) return 1;
        bool same = rc.rays == ra.rays &&
                    memcmp(rc.rgb, ra.rgb, n * 3 * sizeof(float)) == 0;
        printf("scalar vs sse4 (no FMA, 4-wide BVH both): %s\n",
               same ? "identical -> ok" : "DIFFERENT -> FAIL");
        if (!same) status = 1;
        lanes_render_result_free(&rc);
    }
    /* The public API (as `lanes render` uses it) renders the same image as
     * the kernel table, bit for bit: same set, same BVH, same kernels. */
    {
        lanes_device dev;
        lanes_accel api = NULL;
        char config[64];
        snprintf(config, sizeof config, "isa=%s,accuracy=%s", lanes_isa_name(b), lanes_accuracy_name(accuracy));
        lanes_status st = lanes_device_create(config, &dev);
        if (st == LANES_OK) st = lanes_render_api_accel_create(&scene, dev, &api);
        lanes_render_options opt = wide_options(b, size);
        opt.api_accel = api;
        lanes_render_result rp;
        lanes_render_accel none;
        memset(&none, 0, sizeof none);
        bool ok = st == LANES_OK && lanes_render(&scene, &none, &opt, &rp, &err) == LANES_OK;
        bool same = ok && rp.rays == rb.rays && memcmp(rp.rgb, rb.rgb, n * 3 * sizeof(float)) == 0;
        printf("%s through the public API vs the kernel table: %s (trace %.3f s vs %.3f s; timing "
               "is reported, not tested)\n",
               lanes_isa_name(b), !ok ? "FAIL (could not render)" : same ? "identical -> ok" : "DIFFERENT -> FAIL",
               ok ? rp.seconds : 0.0, rb.seconds);
        if (!ok) printf("  %s %s\n", lanes_last_error_message(), err.message);
        if (!same) status = 1;
        if (ok) lanes_render_result_free(&rp);
        lanes_accel_release(api);
        lanes_device_release(dev);
    }
    lanes_render_result_free(&ra);
    lanes_render_result_free(&rb);
    lanes_scene_free(&scene);
    return status;
}
