/* The path tracer (trace/paths.c) against closed-form answers, at the
 * scalar set and the best set this CPU runs, both single-path methods:
 *   - a convex Lambert sphere of albedo rho under a uniform background L:
 *     every path that hits it leaves after one bounce, so each pixel is
 *     L (k + (spp - k) rho) / spp for its k missing samples, to float
 *     rounding;
 *   - inside a closed Lambert sphere of albedo rho that emits Le: the
 *     radiance is Le / (1 - rho) everywhere, the image mean within 4
 *     standard errors (Russian roulette and all bounces to depth 32);
 *   - a point light of intensity I over a Lambert plane: each pixel
 *     rho I cos / (pi r^2), computed in double from the pixel's ray;
 *   - a visible square light over a Lambert plane: rho E / pi with E from
 *     Lambert's polygon formula, the mean relative error within 4
 *     standard errors (and not doubled by bounces into the square);
 *   - single and single-1lane give the same image at the scalar set;
 *     packet and stream the same image, rays and paths as single-1lane at
 *     each set, with more live lanes per shading call; the counters add
 *     up; the closed-form scenes above run through every method;
 *   - bad options are refused with a message. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "build/camera.h"
#include "build/scenes_builtin.h"
#include "harness.h"
#include "trace/paths.h"

static void add_object(lanes_scene *s, const char *name, int detail, double scale, uint32_t material)
{
    lanes_mesh m;
    lanes_error err;
    if (!CHECK(lanes_builtin_object(name, detail, &m, &err) == LANES_OK, "%s: %s", name, err.message)) return;
    lanes_xform xf;
    const double t[3] = {0, 0, 0}, sc[3] = {scale, scale, scale};
    lanes_xform_trs(&xf, t, NULL, sc);
    CHECK(lanes_scene_add_mesh(s, &m, &xf, material, name, &err) == LANES_OK, "%s: %s", name, err.message);
    lanes_mesh_free(&m);
}

static uint32_t add_diffuse(lanes_scene *s, const char *name, const float rho[3], const float le[3])
{
    lanes_material m;
    memset(&m, 0, sizeof m);
    snprintf(m.name, sizeof m.name, "%s", name);
    m.kind = LANES_MAT_DIFFUSE;
    m.ior = 1.0f;
    memcpy(m.color, rho, sizeof m.color);
    if (le) memcpy(m.emission, le, sizeof m.emission);
    uint32_t index = 0;
    lanes_error err;
    CHECK(lanes_scene_add_material(s, &m, &index, &err) == LANES_OK, "material %s: %s", name, err.message);
    return index;
}

static void set_camera(lanes_scene *s, const float eye[3], const float target[3], const float up[3], float fov, int size)
{
    memcpy(s->camera.eye, eye, 12);
    memcpy(s->camera.target, target, 12);
    memcpy(s->camera.up, up, 12);
    s->camera.fov_y_degrees = fov;
    s->camera.width = s->camera.height = size;
}

/* Renders; false (with a failed check) when it could not. */
static bool render(const lanes_scene *s, lanes_isa isa, lanes_paths_method method, int spp, int depth,
                   const float *background, lanes_paths_result *out)
{
    lanes_render_accel accel;
    lanes_error err;
    if (!CHECK(lanes_render_accel_build(s, lanes_kernels_for(isa), false, 0, &accel, &err) == LANES_OK, "accel: %s",
               err.message))
        return false;
    lanes_paths_options o;
    lanes_paths_default_options(&o);
    o.isa = isa, o.method = method, o.spp = spp, o.depth = depth, o.threads = 2;
    o.stream = 256; /* the smallest: a tile's slots refilled many times */
    if (background) {
        o.uniform_background = true;
        memcpy(o.background, background, sizeof o.background);
    }
    lanes_status st = lanes_paths_render(s, &accel, &o, out, &err);
    lanes_render_accel_free(&accel);
    return CHECK(st == LANES_OK, "%s %s: %s", lanes_isa_name(isa), lanes_paths_method_name(method), err.message);
}

static void convex_sphere(lanes_isa isa, lanes_paths_method method)
{
    lanes_scene s;
    lanes_scene_init(&s);
    const float rho[3] = {0.5f, 0.3f, 0.8f}, L[3] = {1.0f, 2.0f, 0.5f};
    add_object(&s, "sphere", 3, 1.0, add_diffuse(&s, "rho", rho, NULL));
    set_camera(&s, (const float[3]){0, 0, 4}, (const float[3]){0, 0, 0}, (const float[3]){0, 1, 0}, 40.0f, 48);
    enum { SPP = 4 };
    lanes_paths_result r;
    if (render(&s, isa, method, SPP, 8, L, &r)) {
        long bad = 0, hit = 0;
        for (int p = 0; p < r.width * r.height; p++) {
            bool found = false;
            for (int k = 0; k <= SPP && !found; k++) {
                bool all = true;
                for (int c = 0; c < 3; c++) {
                    double want = L[c] * (k + (SPP - k) * (double)rho[c]) / SPP;
                    all = all && fabs(r.rgb[3 * p + c] - want) <= 2e-6 * want;
                }
                found = all;
                hit += all && k < SPP;
            }
            bad += !found;
        }
        CHECK(bad == 0, "%s %s: %ld pixels of the sphere under a uniform sky are not L (k + (spp - k) rho) / spp",
              lanes_isa_name(isa), lanes_paths_method_name(method), bad);
        CHECK(hit > r.width * r.height / 8, "%s: the sphere covers only %ld pixels", lanes_isa_name(isa), hit);
        lanes_paths_result_free(&r);
    }
    lanes_scene_free(&s);
}

static void inside_sphere(lanes_isa isa, lanes_paths_method method)
{
    lanes_scene s;
    lanes_scene_init(&s);
    const float rho[3] = {0.5f, 0.25f, 0.75f}, le[3] = {1.0f, 1.0f, 1.0f};
    add_object(&s, "sphere", 3, 1.0, add_diffuse(&s, "glowing", rho, le));
    set_camera(&s, (const float[3]){0, 0, 0}, (const float[3]){0, 0, -1}, (const float[3]){0, 1, 0}, 60.0f, 32);
    lanes_paths_result r;
    if (render(&s, isa, method, 16, LANES_PATHS_MAX_DEPTH, NULL, &r)) {
        int n = r.width * r.height;
        for (int c = 0; c < 3; c++) {
            double sum = 0.0, sum2 = 0.0;
            for (int p = 0; p < n; p++) sum += r.rgb[3 * p + c], sum2 += (double)r.rgb[3 * p + c] * r.rgb[3 * p + c];
            double mean = sum / n, se = sqrt(fmax(0.0, sum2 / n - mean * mean) / n);
            double want = le[c] / (1.0 - rho[c]);
            printf("  %s %s: inside a glowing sphere, channel %d: %.4f +- %.4f, expected %.4f\n", lanes_isa_name(isa),
                   lanes_paths_method_name(method), c, mean, se, want);
            CHECK(fabs(mean - want) <= 4.0 * se, "%s %s: inside a sphere of albedo %g emitting %g: mean %.4f +- %.4f, expected %.4f",
                  lanes_isa_name(isa), lanes_paths_method_name(method), (double)rho[c], (double)le[c], mean, se, want);
        }
        lanes_paths_result_free(&r);
    }
    lanes_scene_free(&s);
}

static void point_light(lanes_isa isa, lanes_paths_method method)
{
    lanes_scene s;
    lanes_scene_init(&s);
    const float rho[3] = {0.7f, 0.4f, 0.2f}, black[3] = {0, 0, 0};
    add_object(&s, "plane", -1, 4.0, add_diffuse(&s, "floor", rho, NULL));
    lanes_point_light light = {{0.3f, 1.0f, -0.2f}, {3.0f, 2.0f, 1.0f}};
    lanes_error err;
    CHECK(lanes_scene_add_point_light(&s, &light, &err) == LANES_OK, "light: %s", err.message);
    const float eye[3] = {0, 3, 0};
    set_camera(&s, eye, (const float[3]){0, 0, 0}, (const float[3]){0, 0, -1}, 60.0f, 40);
    lanes_paths_result r;
    if (render(&s, isa, method, 1, 2, black, &r)) {
        lanes_view v = lanes_view_make(&s.camera, r.width, r.height);
        long bad = 0, compared = 0;
        for (int y = 0; y < r.height; y++)
            for (int x = 0; x < r.width; x++) {
                vec3 d = lanes_view_dir(&v, (float)x + 0.5f, (float)y + 0.5f);
                double t = -eye[1] / (double)d.y, px = eye[0] + t * d.x, pz = eye[2] + t * d.z;
                if (!(d.y < 0.0f) || fabs(px) > 3.9 || fabs(pz) > 3.9) continue;
                double lx = light.position[0] - px, ly = light.position[1], lz = light.position[2] - pz;
                double r2 = lx * lx + ly * ly + lz * lz, cosine = ly / sqrt(r2);
                compared++;
                for (int c = 0; c < 3; c++) {
                    double want = rho[c] / 3.14159265358979323846 * light.intensity[c] * cosine / r2;
                    bad += fabs(r.rgb[3 * (y * r.width + x) + c] - want) > 1e-4 * want;
                }
            }
        CHECK(bad == 0 && compared > 500, "%s %s: %ld of %ld plane pixels differ from rho I cos / (pi r^2)",
              lanes_isa_name(isa), lanes_paths_method_name(method), bad, compared);
        lanes_paths_result_free(&r);
    }
    lanes_scene_free(&s);
}

/* Irradiance at x (on a surface of normal +y) from a uniformly emitting
 * polygon (Lambert's formula): Le / 2 times the sum over the edges of
 * the angle they subtend, projected on the normal. */
static double polygon_irradiance(const double x[3], const double v[4][3], double le)
{
    double sum = 0.0;
    for (int i = 0; i < 4; i++) {
        double a[3], b[3], la = 0.0, lb = 0.0;
        for (int k = 0; k < 3; k++) a[k] = v[i][k] - x[k], b[k] = v[(i + 1) % 4][k] - x[k];
        for (int k = 0; k < 3; k++) la += a[k] * a[k], lb += b[k] * b[k];
        la = sqrt(la), lb = sqrt(lb);
        for (int k = 0; k < 3; k++) a[k] /= la, b[k] /= lb;
        double c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
        double lc = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        double angle = acos(fmax(-1.0, fmin(1.0, a[0] * b[0] + a[1] * b[1] + a[2] * b[2])));
        sum += angle * c[1] / lc;
    }
    return 0.5 * le * fabs(sum);
}

/* A square light facing down over a Lambert plane, visible (its two
 * triangles in the scene): each plane pixel is rho E / pi, E by Lambert's
 * formula, within 4 standard errors over the image (the shadow rays sample
 * the square); rays that bounce off the plane into the square must not add
 * its emission again (that would double the light). */
static void area_light(lanes_isa isa, lanes_paths_method method)
{
    lanes_scene s;
    lanes_scene_init(&s);
    const float rho[3] = {0.6f, 0.6f, 0.6f};
    add_object(&s, "plane", -1, 6.0, add_diffuse(&s, "floor", rho, NULL));
    /* corner (-0.5, 1, -0.5), edges along x then z: edge_u x edge_v points down */
    lanes_area_light l = {{-0.5f, 1.0f, -0.5f}, {1.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 1.0f}, {5.0f, 5.0f, 5.0f}};
    lanes_error err;
    CHECK(lanes_scene_add_area_light_quad(&s, &l, true, &err) == LANES_OK, "light: %s", err.message);
    const float eye[3] = {0.0f, 0.9f, 3.5f};
    set_camera(&s, eye, (const float[3]){0, 0, 0}, (const float[3]){0, 1, 0}, 20.0f, 32);
    lanes_paths_result r;
    const float black[3] = {0, 0, 0};
    if (render(&s, isa, method, 16, 4, black, &r)) {
        const double v[4][3] = {{-0.5, 1, -0.5}, {-0.5, 1, 0.5}, {0.5, 1, 0.5}, {0.5, 1, -0.5}};
        lanes_view view = lanes_view_make(&s.camera, r.width, r.height);
        double sum = 0.0, sum2 = 0.0;
        long n = 0;
        for (int y = 0; y < r.height; y++)
            for (int x = 0; x < r.width; x++) {
                /* the mean over the pixel, as its jittered samples see it
                 * (at the centre alone, the far pixels' footprints bias
                 * the mean by 0.5%) */
                double want = 0.0;
                bool inside = true;
                for (int k = 0; k < 64 && inside; k++) {
                    vec3 d = lanes_view_dir(&view, (float)x + ((float)(k % 8) + 0.5f) / 8.0f,
                                            (float)y + ((float)(k / 8) + 0.5f) / 8.0f);
                    double t = -eye[1] / (double)d.y, p[3] = {eye[0] + t * d.x, 0.0, eye[2] + t * d.z};
                    inside = d.y < 0.0f && fabs(p[0]) <= 5.5 && fabs(p[2]) <= 5.5;
                    want += rho[0] / 3.14159265358979323846 * polygon_irradiance(p, v, l.emission[0]) / 64.0;
                }
                if (!inside) continue;
                /* relative error of the pixel, averaged */
                double e = (r.rgb[3 * (y * r.width + x)] - want) / want;
                sum += e, sum2 += e * e, n++;
            }
        double mean = sum / (double)n, se = sqrt(fmax(0.0, sum2 / (double)n - mean * mean) / (double)n);
        printf("  %s %s: under a square light, relative error %.4f +- %.4f over %ld pixels\n", lanes_isa_name(isa),
               lanes_paths_method_name(method), mean, se, n);
        CHECK(n > 500 && fabs(mean) <= 4.0 * se, "%s %s: the plane under a square light is off by %.4f +- %.4f of rho E / pi",
              lanes_isa_name(isa), lanes_paths_method_name(method), mean, se);
        lanes_paths_result_free(&r);
    }
    lanes_scene_free(&s);
}

/* The same image from both methods at the scalar set (the same kernels),
 * and the shading counters. */
static void methods_and_counters(lanes_isa best)
{
    lanes_scene s;
    lanes_error err;
    if (!CHECK(lanes_builtin_scene("default", &s, &err) == LANES_OK, "default scene: %s", err.message)) return;
    lanes_paths_result a, b;
    bool ok = render(&s, LANES_ISA_SCALAR, LANES_PATHS_SINGLE, 2, 8, NULL, &a);
    ok = render(&s, LANES_ISA_SCALAR, LANES_PATHS_SINGLE_1LANE, 2, 8, NULL, &b) && ok;
    if (ok) {
        CHECK(memcmp(a.rgb, b.rgb, (size_t)a.width * (size_t)a.height * 3 * sizeof(float)) == 0,
              "scalar: single and single-1lane differ");
        CHECK(a.paths == (uint64_t)a.width * (uint64_t)a.height * 2 && a.rays_by_depth[0] == a.paths,
              "paths %llu, camera rays %llu", (unsigned long long)a.paths, (unsigned long long)a.rays_by_depth[0]);
        CHECK(a.shade_slots == a.shade_calls && a.shade_live == a.shade_calls, "scalar shading: %llu calls, %llu slots",
              (unsigned long long)a.shade_calls, (unsigned long long)a.shade_slots);
        CHECK(a.shadow_rays > 0 && a.rays_by_depth[1] > 0, "no shadow or extension rays in the default scene");
        lanes_paths_result_free(&a), lanes_paths_result_free(&b);
    }
    /* packets: the same radiance as single-1lane at the same set, bit for
     * bit, and the same rays; more live lanes per shading call */
    lanes_isa sets[2] = {LANES_ISA_SCALAR, best};
    for (int i = 0; i < 4; i++) {
        /* packets, then streams (of 256 paths, refilled many times a tile) */
        lanes_paths_method other = i < 2 ? LANES_PATHS_PACKET : LANES_PATHS_STREAM;
        lanes_paths_result one, packet;
        bool both = render(&s, sets[i % 2], LANES_PATHS_SINGLE_1LANE, 2, 8, NULL, &one);
        both = render(&s, sets[i % 2], other, 2, 8, NULL, &packet) && both;
        if (!both) continue;
        CHECK(memcmp(one.rgb, packet.rgb, (size_t)one.width * (size_t)one.height * 3 * sizeof(float)) == 0,
              "%s: %s and single-1lane images differ", lanes_isa_name(sets[i % 2]), lanes_paths_method_name(other));
        CHECK(memcmp(one.rays_by_depth, packet.rays_by_depth, sizeof one.rays_by_depth) == 0 &&
                  one.shadow_rays == packet.shadow_rays && one.paths == packet.paths,
              "%s: %s and single-1lane trace different rays", lanes_isa_name(sets[i % 2]), lanes_paths_method_name(other));
        double u1 = (double)one.shade_live / (double)one.shade_slots, up = (double)packet.shade_live / (double)packet.shade_slots;
        int lanes = lanes_kernels_for(sets[i % 2])->lanes;
        printf("  %s: shading utilisation single-1lane %.3f, %s %.3f\n", lanes_isa_name(sets[i % 2]), u1, lanes_paths_method_name(other), up);
        CHECK(lanes == 1 ? up == 1.0 : (up > u1 && up < 1.0), "%s: %s utilisation %.3f, single-1lane %.3f",
              lanes_isa_name(sets[i % 2]), lanes_paths_method_name(other), up, u1);
        lanes_paths_result_free(&one), lanes_paths_result_free(&packet);
    }
    lanes_paths_result w;
    if (render(&s, best, LANES_PATHS_SINGLE_1LANE, 1, 8, NULL, &w)) {
        int lanes = lanes_kernels_for(best)->lanes;
        CHECK(w.shade_slots == w.shade_calls * (uint64_t)lanes && w.shade_live == w.shade_calls,
              "%s single-1lane: %llu calls, %llu slots, %llu live", lanes_isa_name(best),
              (unsigned long long)w.shade_calls, (unsigned long long)w.shade_slots, (unsigned long long)w.shade_live);
        lanes_paths_result_free(&w);
    }
    /* refusals */
    lanes_render_accel accel;
    if (CHECK(lanes_render_accel_build(&s, lanes_kernels_for(best), false, 0, &accel, &err) == LANES_OK, "%s",
              err.message)) {
        lanes_paths_options o;
        lanes_paths_result r;
        struct {
            int spp, depth;
            float background;
            const char *says;
        } bad[] = {{0, 8, 0, "samples per pixel"}, {1, 0, 0, "depth 0"}, {1, 33, 0, "depth 33"}, {1, 8, NAN, "background"},
                   {1, 8, -1, "background"}};
        for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
            lanes_paths_default_options(&o);
            o.isa = best, o.spp = bad[i].spp, o.depth = bad[i].depth;
            o.uniform_background = bad[i].background != 0.0f;
            o.background[0] = bad[i].background;
            lanes_status st = lanes_paths_render(&s, &accel, &o, &r, &err);
            CHECK(st == LANES_ERR_BAD_INPUT && strstr(err.message, bad[i].says), "refusal %zu: status %d, '%s'", i, st,
                  err.message);
        }
        static const int bad_stream[] = {0, 240, 1000, 65552};
        for (size_t i = 0; i < sizeof bad_stream / sizeof bad_stream[0]; i++) {
            lanes_paths_default_options(&o);
            o.isa = best, o.method = LANES_PATHS_STREAM, o.stream = bad_stream[i];
            lanes_status st = lanes_paths_render(&s, &accel, &o, &r, &err);
            CHECK(st == LANES_ERR_BAD_INPUT && strstr(err.message, "stream size"), "stream of %d: status %d, '%s'",
                  bad_stream[i], st, err.message);
        }
        lanes_render_accel_free(&accel);
    }
    lanes_scene_free(&s);
}

int main(void)
{
    lanes_isa best = lanes_isa_current();
    lanes_isa sets[2] = {LANES_ISA_SCALAR, best};
    printf("test_paths: scalar and %s\n", lanes_isa_name(best));
    for (int i = 0; i < (best == LANES_ISA_SCALAR ? 1 : 2); i++)
        for (int m = 0; m < LANES_PATHS_METHOD_COUNT; m++) {
            convex_sphere(sets[i], (lanes_paths_method)m);
            inside_sphere(sets[i], (lanes_paths_method)m);
            point_light(sets[i], (lanes_paths_method)m);
            area_light(sets[i], (lanes_paths_method)m);
        }
    methods_and_counters(best);
    return harness_summary("test_paths");
}
