/* The path tracer on scenes with many materials (tests/data/scenes/ok/
 * materials.json: conductors, plastics, all four textures, an emitting
 * diffuse; and the default scene with 100 clustered materials), at every
 * set this CPU runs:
 *   - packet and stream give the radiance of single-1lane bit for bit per
 *     pixel, the same rays per depth, and finish every path they begin
 *     (the stream's books balance after every stage);
 *   - each set's image agrees with the scalar set's single method (scalar
 *     shading; FMA and wider BVHs round differently, and a rare path takes
 *     another branch): the image mean within 4 standard errors, and per
 *     pixel and channel |z| <= 4 but for a tail of at most 1 in 1000, the
 *     standard errors from both images' per-sample variances; and, as the
 *     samples use the same random numbers at every set, paired: at least
 *     99% of pixel channels within 1e-4 relative of scalar shading's (a
 *     1% bias in one BSDF hides in the noise of the first test, not in
 *     this one);
 *   - the sampling calls' utilisation counters equal a recount from the
 *     materials of the hits each trace call returned (an intersector
 *     around the set's traversal): per call, a stream shades each
 *     material's n_m rays in ceil(n_m / W) calls, a packet each material
 *     present in one; live lanes sum(n_m) of the slots W * calls;
 *   - packet shading utilisation on the 100-material scene falls as the
 *     width grows, 4 > 8 > 16 lanes (printed).
 * With --builtin NAME (a scene of the CGAL meshes, such as sponza-bunny),
 * the exactness and the recount on that scene with 100 clustered materials
 * alone; 77 (skipped) while the meshes are not fetched.
 * Usage: test_paths_sets DATA_DIR [--builtin NAME] */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "build/material_assign.h"
#include "build/scene_load.h"
#include "build/scenes_builtin.h"
#include "harness.h"
#include "trace/paths.h"

enum { SIZE = 64, SPP_EXACT = 2, SPP_STATS = 16 };

static bool render_with(const lanes_scene *s, lanes_isa isa, lanes_paths_method method, int spp,
                        const lanes_paths_intersector *x, lanes_paths_result *out)
{
    lanes_render_accel accel;
    lanes_error err;
    if (!CHECK(lanes_render_accel_build(s, lanes_kernels_for(isa), false, 0, &accel, &err) == LANES_OK, "accel: %s",
               err.message))
        return false;
    lanes_paths_options o;
    lanes_paths_default_options(&o);
    o.isa = isa, o.method = method, o.spp = spp, o.threads = 2;
    o.width = o.height = SIZE;
    o.stream = 256; /* the smallest: a tile's slots refilled many times */
    o.accuracy = LANES_ACCURACY_DEFAULT;
    o.intersector = x;
    lanes_status st = lanes_paths_render(s, &accel, &o, out, &err);
    lanes_render_accel_free(&accel);
    return CHECK(st == LANES_OK, "%s %s: %s", lanes_isa_name(isa), lanes_paths_method_name(method), err.message);
}

static bool render(const lanes_scene *s, lanes_isa isa, lanes_paths_method method, int spp, lanes_paths_result *out)
{
    return render_with(s, isa, method, spp, NULL, out);
}

static size_t image_bytes(const lanes_paths_result *r) { return (size_t)r->width * (size_t)r->height * 3 * sizeof(float); }

/* packet and stream against single-1lane at one set */
static void exact(const char *scene, const lanes_scene *s, lanes_isa isa)
{
    lanes_paths_result one;
    if (!render(s, isa, LANES_PATHS_SINGLE_1LANE, SPP_EXACT, &one)) return;
    CHECK(one.paths == (uint64_t)SIZE * SIZE * SPP_EXACT && one.paths_finished == one.paths,
          "%s %s single-1lane: %llu paths begun, %llu finished", scene, lanes_isa_name(isa),
          (unsigned long long)one.paths, (unsigned long long)one.paths_finished);
    for (int m = LANES_PATHS_PACKET; m <= LANES_PATHS_STREAM; m++) {
        lanes_paths_result r;
        const char *name = lanes_paths_method_name((lanes_paths_method)m);
        if (!render(s, isa, (lanes_paths_method)m, SPP_EXACT, &r)) continue;
        CHECK(memcmp(one.rgb, r.rgb, image_bytes(&r)) == 0, "%s %s: %s and single-1lane images differ", scene,
              lanes_isa_name(isa), name);
        CHECK(memcmp(one.rays_by_depth, r.rays_by_depth, sizeof r.rays_by_depth) == 0 && one.shadow_rays == r.shadow_rays,
              "%s %s: %s and single-1lane trace different rays", scene, lanes_isa_name(isa), name);
        CHECK(r.paths == one.paths && r.paths_finished == r.paths, "%s %s %s: %llu paths begun, %llu finished", scene,
              lanes_isa_name(isa), name, (unsigned long long)r.paths, (unsigned long long)r.paths_finished);
        CHECK(r.accounting_errors == 0, "%s %s %s: after %llu stages the paths made were not the finished plus those in flight",
              scene, lanes_isa_name(isa), name, (unsigned long long)r.accounting_errors);
        lanes_paths_result_free(&r);
    }
    lanes_paths_result_free(&one);
}

/* A pixel channel's standard error: the per-sample variance over spp. */
static double std_error(const lanes_paths_result *r, size_t i)
{
    double m = r->rgb[i], var = (double)r->rgb2[i] - m * m;
    return sqrt(fmax(var, 0.0) / SPP_STATS);
}

/* One set's image against the scalar set's single method. */
static void agrees(const char *scene, const lanes_paths_result *ref, const lanes_paths_result *r, lanes_isa isa)
{
    size_t n = (size_t)r->width * (size_t)r->height * 3;
    double diff = 0.0, var = 0.0, worst = 0.0;
    size_t tail = 0, apart = 0;
    for (size_t i = 0; i < n; i++) {
        apart += fabs((double)r->rgb[i] - ref->rgb[i]) > 1e-4 * fabs((double)ref->rgb[i]) + 1e-7;
        double d = (double)r->rgb[i] - ref->rgb[i], ea = std_error(r, i), eb = std_error(ref, i);
        diff += d, var += ea * ea + eb * eb;
        /* a pixel every sample of which saw the same constant (the sky)
         * differs by rounding only: its error is float's, not the noise's */
        double sigma = sqrt(ea * ea + eb * eb) + 1e-6 * fabs((double)ref->rgb[i]) + 1e-30;
        double z = fabs(d) / sigma;
        worst = fmax(worst, z);
        tail += z > 4.0;
    }
    double z_mean = fabs(diff) / sqrt(var);
    printf("  %s %s against scalar single: image mean z %.2f, worst pixel z %.2f, %zu of %zu channels beyond 4, "
           "%zu beyond 1e-4 relative\n",
           scene, lanes_isa_name(isa), z_mean, worst, tail, n, apart);
    CHECK(z_mean <= 4.0, "%s %s: the image mean differs from scalar shading's by %.2f standard errors", scene,
          lanes_isa_name(isa), z_mean);
    CHECK(tail * 1000 <= n, "%s %s: %zu of %zu pixel channels differ from scalar shading's by over 4 standard errors",
          scene, lanes_isa_name(isa), tail, n);
    CHECK(apart * 100 <= n, "%s %s: %zu of %zu pixel channels differ from scalar shading's by over 1e-4 relative", scene,
          lanes_isa_name(isa), apart, n);
}

/* The recount: the set's own traversal, then the shading calls the hits
 * must have led to, from their materials alone. */
typedef struct {
    const lanes_scene *scene;
    const lanes_render_accel *accel;
    const lanes_kernels *k;
    bool stream; /* else packet */
    pthread_mutex_t lock;
    uint64_t slots, live;
    bool out_of_memory;
} recount;

static void recount_trace(void *ctx, const lanes_ray *rays, size_t n, lanes_hit *hits)
{
    recount *rc = ctx;
    rc->k->trace_wide(&rc->accel->wide, LANES_ACCURACY_DEFAULT, rays, n, hits, NULL);
    const lanes_scene *s = rc->scene;
    uint32_t *per_material = calloc(s->material_count, sizeof *per_material);
    uint64_t slots = 0, live = 0, w = (uint64_t)rc->k->lanes;
    for (size_t i = 0; per_material && i < n; i++)
        if (hits[i].prim != LANES_NO_HIT && s->materials[s->material_of[hits[i].prim]].kind != LANES_MAT_EMISSIVE)
            per_material[s->material_of[hits[i].prim]]++;
    for (size_t m = 0; per_material && m < s->material_count; m++) {
        if (!per_material[m]) continue;
        live += per_material[m];
        slots += rc->stream ? w * ((per_material[m] + w - 1) / w) : w;
    }
    pthread_mutex_lock(&rc->lock);
    rc->slots += slots, rc->live += live;
    rc->out_of_memory = rc->out_of_memory || !per_material;
    pthread_mutex_unlock(&rc->lock);
    free(per_material);
}

static void recount_occluded(void *ctx, const lanes_ray *rays, size_t n, uint8_t *occluded)
{
    recount *rc = ctx;
    rc->k->occluded_wide(&rc->accel->wide, LANES_ACCURACY_DEFAULT, rays, n, occluded, NULL);
}

static void utilisation_recounted(const char *scene, const lanes_scene *s, lanes_isa isa)
{
    lanes_render_accel accel;
    lanes_error err;
    if (!CHECK(lanes_render_accel_build(s, lanes_kernels_for(isa), false, 0, &accel, &err) == LANES_OK, "accel: %s",
               err.message))
        return;
    for (int m = LANES_PATHS_PACKET; m <= LANES_PATHS_STREAM; m++) {
        recount rc = {s, &accel, lanes_kernels_for(isa), m == LANES_PATHS_STREAM, PTHREAD_MUTEX_INITIALIZER, 0, 0, false};
        lanes_paths_intersector x = {"recount", &rc, recount_trace, recount_occluded};
        lanes_paths_result r;
        const char *name = lanes_paths_method_name((lanes_paths_method)m);
        if (render_with(s, isa, (lanes_paths_method)m, SPP_EXACT, &x, &r)) {
            printf("  %s %s %s: sampling utilisation %.3f (%llu of %llu lanes), recount %.3f\n", scene,
                   lanes_isa_name(isa), name, (double)r.sample_live / (double)r.sample_slots,
                   (unsigned long long)r.sample_live, (unsigned long long)r.sample_slots,
                   (double)rc.live / (double)rc.slots);
            CHECK(!rc.out_of_memory && r.sample_live == rc.live && r.sample_slots == rc.slots && rc.slots > 0,
                  "%s %s %s: sampling counted %llu live of %llu slots, the hits' materials give %llu of %llu", scene,
                  lanes_isa_name(isa), name, (unsigned long long)r.sample_live, (unsigned long long)r.sample_slots,
                  (unsigned long long)rc.live, (unsigned long long)rc.slots);
            CHECK(r.shade_slots >= r.sample_slots && r.shade_live >= r.sample_live, "%s %s %s: sampling above the total",
                  scene, lanes_isa_name(isa), name);
            lanes_paths_result_free(&r);
        }
        pthread_mutex_destroy(&rc.lock);
    }
    lanes_render_accel_free(&accel);
}

/* The set of each width this CPU runs, best first. */
static lanes_isa runs_with_lanes(int lanes)
{
    for (int i = 0; i < LANES_ISA_COUNT; i++) {
        lanes_isa isa = lanes_isa_ranked()[i];
        const lanes_kernels *k = lanes_kernels_for(isa);
        if (k && lanes_isa_supported(isa) && k->lanes == lanes) return isa;
    }
    return LANES_ISA_COUNT;
}

static void utilisation_by_width(const lanes_scene *s)
{
    double u[3] = {0, 0, 0};
    const int widths[3] = {4, 8, 16};
    for (int i = 0; i < 3; i++) {
        lanes_isa isa = runs_with_lanes(widths[i]);
        lanes_paths_result r;
        if (isa == LANES_ISA_COUNT) {
            printf("  no %d-lane set runs here: utilisation at %d lanes not measured\n", widths[i], widths[i]);
            continue;
        }
        if (!render(s, isa, LANES_PATHS_PACKET, SPP_EXACT, &r)) continue;
        u[i] = (double)r.shade_live / (double)r.shade_slots;
        printf("  100 materials, packet shading utilisation at %d lanes (%s): %.3f\n", widths[i], lanes_isa_name(isa), u[i]);
        lanes_paths_result_free(&r);
    }
    for (int i = 0; i + 1 < 3; i++)
        if (u[i] > 0.0 && u[i + 1] > 0.0)
            CHECK(u[i] > u[i + 1], "packet utilisation %.3f at %d lanes, %.3f at %d", u[i], widths[i], u[i + 1],
                  widths[i + 1]);
}

/* The exactness and the recount at every set on one built-in mesh scene. */
static int builtin_scene(const char *name)
{
    if (!lanes_builtin_meshes_available()) {
        printf("skipped: the CGAL meshes are not in %s (run cmake/fetch_meshes.sh)\n", lanes_mesh_dir());
        return 77;
    }
    lanes_scene s;
    lanes_error err;
    char label[160];
    snprintf(label, sizeof label, "%s+100", name);
    if (!CHECK(lanes_builtin_scene(name, &s, &err) == LANES_OK, "%s: %s", name, err.message))
        return harness_summary("test_paths_sets");
    if (CHECK(lanes_scene_assign_materials(&s, 100, LANES_ASSIGN_CLUSTER, &err) == LANES_OK, "%s with 100 materials: %s",
              name, err.message)) {
        for (int i = 0; i < LANES_ISA_COUNT; i++) {
            lanes_isa isa = lanes_isa_ranked()[i];
            if (!lanes_kernels_for(isa) || !lanes_isa_supported(isa)) continue;
            exact(label, &s, isa);
            utilisation_recounted(label, &s, isa);
        }
    }
    lanes_scene_free(&s);
    return harness_summary("test_paths_sets");
}

int main(int argc, char **argv)
{
    if (argc == 4 && strcmp(argv[2], "--builtin") == 0) return builtin_scene(argv[3]);
    if (argc != 2) {
        fprintf(stderr, "usage: %s DATA_DIR [--builtin NAME]\n", argv[0]);
        return 2;
    }
    char path[4096];
    snprintf(path, sizeof path, "%s/scenes/ok/materials.json", argv[1]);
    lanes_scene scenes[2];
    const char *names[2] = {"materials.json", "default+100"};
    lanes_error err;
    if (!CHECK(lanes_scene_load(path, &scenes[0], &err) == LANES_OK, "%s", err.message)) return harness_summary("test_paths_sets");
    if (!CHECK(lanes_builtin_scene("default", &scenes[1], &err) == LANES_OK &&
                   lanes_scene_assign_materials(&scenes[1], 100, LANES_ASSIGN_CLUSTER, &err) == LANES_OK,
               "default scene with 100 materials: %s", err.message)) {
        lanes_scene_free(&scenes[0]);
        return harness_summary("test_paths_sets");
    }
    for (int i = 0; i < LANES_ISA_COUNT; i++) {
        lanes_isa isa = lanes_isa_ranked()[i];
        if (!lanes_kernels_for(isa) || !lanes_isa_supported(isa)) {
            printf("  %s: not run here\n", lanes_isa_name(isa));
            continue;
        }
        for (int k = 0; k < 2; k++) exact(names[k], &scenes[k], isa);
        utilisation_recounted(names[1], &scenes[1], isa);
    }
    lanes_paths_result ref;
    if (render(&scenes[0], LANES_ISA_SCALAR, LANES_PATHS_SINGLE, SPP_STATS, &ref)) {
        for (int i = 0; i < LANES_ISA_COUNT; i++) {
            lanes_isa isa = lanes_isa_ranked()[i];
            lanes_paths_result r;
            if (!lanes_kernels_for(isa) || !lanes_isa_supported(isa) || isa == LANES_ISA_SCALAR) continue;
            if (!render(&scenes[0], isa, LANES_PATHS_SINGLE_1LANE, SPP_STATS, &r)) continue;
            agrees(names[0], &ref, &r, isa);
            lanes_paths_result_free(&r);
        }
        lanes_paths_result_free(&ref);
    }
    utilisation_by_width(&scenes[1]);
    lanes_scene_free(&scenes[0]);
    lanes_scene_free(&scenes[1]);
    return harness_summary("test_paths_sets");
}
