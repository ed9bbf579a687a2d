/* The scene plan (trace/scene_plan.h) and the accuracy modes in rendering:
 *
 * 1. Decisions from content: a scene turns on exactly the passes and hit
 *    data its materials and lights need; the accuracy mode comes from the
 *    caller, else the scene file, else the default.
 * 2. The robust recommendation: a sphere at the origin does not get it, the
 *    same sphere 1e5 units away does, and the threshold sits where the
 *    fixed offset falls below the offset robust mode's error bound gives.
 * 3. What the recommendation is for: the far sphere of
 *    tests/data/scenes/ok/far_robust.json, rendered in default mode, is
 *    darkened by shadow acne (secondary rays hitting the surface they
 *    leave); in robust mode it is lit like the same sphere at the origin.
 * 4. Without lights and mirrors no hit geometry is read, and the image is
 *    still right: ambient light on the hit material.
 * 5. Through the API: both renderers' default options take the scene
 *    file's mode (the far sphere renders exactly as in robust mode), and an
 *    unknown mode is refused with a message.
 *
 *   test_scene_plan DATA_DIR */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "build/scene_load.h"
#include "build/scenes_builtin.h"
#include "trace/packet_render.h"
#include "trace/render.h"
#include "trace/scene_plan.h"
#include "tests/harness.h"

/* A unit icosphere of one material kind at `offset` on every axis, with
 * `lights` point lights above it. */
static bool sphere_scene(lanes_scene *s, lanes_material_kind kind, int lights, double offset)
{
    lanes_error err;
    lanes_mesh m;
    lanes_scene_init(s);
    lanes_material mat;
    memset(&mat, 0, sizeof mat);
    snprintf(mat.name, sizeof mat.name, "m");
    mat.kind = kind;
    mat.color[0] = mat.color[1] = mat.color[2] = 0.5f;
    mat.ior = 1.5f;
    /* a diffuse material's emission shows too: only the emitter has one */
    if (kind == LANES_MAT_EMISSIVE) mat.emission[0] = mat.emission[1] = mat.emission[2] = 1.0f;
    uint32_t id;
    lanes_xform x;
    const double t[3] = {offset, offset, offset}, one[3] = {1, 1, 1};
    lanes_xform_trs(&x, t, NULL, one);
    bool ok = lanes_builtin_object("sphere", 3, &m, &err) == LANES_OK &&
              lanes_scene_add_material(s, &mat, &id, &err) == LANES_OK &&
              lanes_scene_add_mesh(s, &m, &x, id, "sphere", &err) == LANES_OK;
    lanes_mesh_free(&m);
    for (int i = 0; ok && i < lights; i++) {
        lanes_point_light l = {{(float)offset, (float)offset + 5.0f, (float)offset + 5.0f}, {100, 100, 100}};
        ok = lanes_scene_add_point_light(s, &l, &err) == LANES_OK;
    }
    if (!ok) printf("FAIL: building the sphere scene: %s\n", err.message);
    lanes_scene_frame_camera(s);
    return ok;
}

static void decisions(void)
{
    static const struct {
        lanes_material_kind kind;
        int lights;
        bool shadow, specular, refraction, geometry;
    } cases[] = {
        {LANES_MAT_DIFFUSE, 1, true, false, false, true},
        {LANES_MAT_DIFFUSE, 0, false, false, false, false},
        {LANES_MAT_MIRROR, 1, false, true, false, true},
        {LANES_MAT_GLASS, 0, false, true, true, true},
        {LANES_MAT_EMISSIVE, 2, false, false, false, false},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        lanes_scene s;
        if (!sphere_scene(&s, cases[i].kind, cases[i].lights, 0.0)) {
            harness_fail("the sphere scene did not build (see above)");
            continue;
        }
        lanes_scene_plan p;
        lanes_scene_plan_make(&s, -1, &p);
        CHECK(p.shadow_rays == cases[i].shadow && p.specular_pass == cases[i].specular &&
                  p.refraction == cases[i].refraction && p.hit_geometry == cases[i].geometry,
              "material kind %d with %d lights: shadow %d specular %d refraction %d geometry %d",
              (int)cases[i].kind, cases[i].lights, p.shadow_rays, p.specular_pass, p.refraction,
              p.hit_geometry);
        CHECK(p.accuracy == LANES_ACCURACY_DEFAULT && strcmp(p.accuracy_from, "the default") == 0,
              "no request, no scene file: %s from %s", lanes_accuracy_name(p.accuracy), p.accuracy_from);
        lanes_scene_plan_make(&s, LANES_ACCURACY_FAST, &p);
        CHECK(p.accuracy == LANES_ACCURACY_FAST && strcmp(p.accuracy_from, "--accuracy") == 0,
              "requested fast: %s from %s", lanes_accuracy_name(p.accuracy), p.accuracy_from);
        lanes_scene_free(&s);
    }
    lanes_scene s;
    lanes_error err;
    if (lanes_scene_load("default", &s, &err) == LANES_OK) {
        lanes_scene_plan p;
        lanes_scene_plan_make(&s, -1, &p);
        CHECK(p.shadow_rays && p.specular_pass && p.refraction && p.hit_geometry && !p.recommend_robust,
              "default scene: every pass on, robust not recommended (offset %.3g ulps)", p.epsilon_ulps);
        lanes_scene_free(&s);
    } else {
        CHECK(false, "default scene: %s", err.message);
    }
}

static void recommendation(void)
{
    /* the offset is 1e-5 of the diagonal (about 3.5, so 3.5e-5); robust
     * mode's bound at a coordinate X is 2 sqrt(3) u X plus sqrt(3) ulps of
     * X: 2.7e-5 at X = 65, 5.3e-5 at X = 129 (the ulp doubles at 128) */
    static const struct {
        double offset;
        bool recommend;
    } cases[] = {{0.0, false}, {4.0, false}, {64.0, false}, {128.0, true}, {1e3, true}, {1e5, true}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        lanes_scene s;
        if (!sphere_scene(&s, LANES_MAT_DIFFUSE, 1, cases[i].offset)) {
            harness_fail("the sphere scene did not build (see above)");
            continue;
        }
        lanes_scene_plan p;
        lanes_scene_plan_make(&s, -1, &p);
        CHECK(p.recommend_robust == cases[i].recommend,
              "sphere at %g: recommend robust %d (offset %.3g ulps of %.6g), expected %d", cases[i].offset,
              p.recommend_robust, p.epsilon_ulps, p.extent, cases[i].recommend);
        CHECK(p.recommend_robust == (p.epsilon < p.offset_bound),
              "sphere at %g: the recommendation follows robust mode's bound (%.3g against %.3g)",
              cases[i].offset, p.epsilon, p.offset_bound);
        lanes_scene_free(&s);
    }
}

/* Mean radiance of a 128x128 render of the scene: the single-ray wide
 * scheme, or (packets) the packet renderer's default scheme. */
static double mean_radiance(const lanes_scene *s, lanes_accuracy mode, bool packets)
{
    const lanes_kernels *k = lanes_kernels_current();
    lanes_render_accel a;
    lanes_error err;
    if (lanes_render_accel_build(s, k, true, 0, &a, &err) != LANES_OK) {
        printf("FAIL: %s\n", err.message);
        return NAN;
    }
    lanes_packet_render_options po;
    lanes_packet_render_default_options(&po);
    lanes_render_options o;
    lanes_render_default_options(&o);
    CHECK(o.accuracy == LANES_ACCURACY_FROM_SCENE && po.base.accuracy == LANES_ACCURACY_FROM_SCENE,
          "default render options take the scene file's accuracy mode (have %d, %d)", (int)o.accuracy,
          (int)po.base.accuracy);
    o.accuracy = mode;
    o.width = o.height = 128;
    po.base = o;
    lanes_render_result r;
    double sum = NAN;
    if (packets ? lanes_packet_render(s, &a, &po, &r, NULL, &err) == LANES_OK
                : lanes_render(s, &a, &o, &r, &err) == LANES_OK) {
        sum = 0.0;
        for (size_t i = 0; i < (size_t)r.width * (size_t)r.height * 3; i++) sum += r.rgb[i];
        sum /= (double)r.width * (double)r.height * 3.0;
        lanes_render_result_free(&r);
    } else {
        printf("FAIL: render: %s\n", err.message);
    }
    lanes_render_accel_free(&a);
    return sum;
}

static void far_scene(const char *data_dir)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/scenes/ok/far_robust.json", data_dir);
    lanes_scene far;
    lanes_error err;
    if (lanes_scene_load(path, &far, &err) != LANES_OK) {
        CHECK(false, "%s", err.message);
        return;
    }
    lanes_scene_plan p;
    lanes_scene_plan_make(&far, -1, &p);
    CHECK(far.accuracy == LANES_ACCURACY_ROBUST && p.accuracy == LANES_ACCURACY_ROBUST &&
              strcmp(p.accuracy_from, "the scene file") == 0 && p.recommend_robust,
          "%s: scene asks for %d, plan %s from %s, recommend %d", path, far.accuracy,
          lanes_accuracy_name(p.accuracy), p.accuracy_from, p.recommend_robust);
    lanes_scene_plan_make(&far, LANES_ACCURACY_DEFAULT, &p);
    CHECK(p.accuracy == LANES_ACCURACY_DEFAULT, "--accuracy default overrides the scene file");

    /* the same scene moved to the origin: the reference image */
    lanes_scene near;
    if (lanes_scene_load(path, &near, &err) != LANES_OK) {
        CHECK(false, "%s", err.message);
        lanes_scene_free(&far);
        return;
    }
    for (size_t i = 0; i < near.triangle_count * 9; i += 3) near.verts[i] -= 100000.0f;
    near.point_lights[0].position[0] -= 100000.0f;
    near.camera.eye[0] -= 100000.0f;
    near.camera.target[0] -= 100000.0f;
    double ref = mean_radiance(&near, LANES_ACCURACY_DEFAULT, false);
    double robust = mean_radiance(&far, LANES_ACCURACY_ROBUST, false);
    double plain = mean_radiance(&far, LANES_ACCURACY_DEFAULT, false);
    /* the renders are deterministic, so "from the scene" must match exactly */
    double from_scene = mean_radiance(&far, LANES_ACCURACY_FROM_SCENE, false);
    CHECK(from_scene == robust, "lanes_render with the scene file's mode: %.6f, robust %.6f", from_scene,
          robust);
    double packet_robust = mean_radiance(&far, LANES_ACCURACY_ROBUST, true);
    double packet_from_scene = mean_radiance(&far, LANES_ACCURACY_FROM_SCENE, true);
    double packet_plain = mean_radiance(&far, LANES_ACCURACY_DEFAULT, true);
    CHECK(packet_from_scene == packet_robust && packet_plain != packet_robust,
          "lanes_packet_render with the scene file's mode: %.6f, robust %.6f, default %.6f",
          packet_from_scene, packet_robust, packet_plain);
    printf("far sphere mean radiance: %.5f robust, %.5f default; at the origin %.5f\n", robust, plain, ref);
    /* 1e5 rounds the sphere's vertices to 1/128 (measured: 0.05% darker) */
    CHECK(fabs(robust - ref) <= 0.01 * ref, "robust far sphere %.5f vs %.5f at the origin", robust, ref);
    CHECK(plain < 0.9 * ref, "default mode on the far sphere %.5f is not darkened by acne (origin %.5f): "
          "then the robust recommendation lacks its reason", plain, ref);
    lanes_scene_free(&near);
    lanes_scene_free(&far);
}

static void no_geometry_needed(void)
{
    lanes_scene s;
    if (!sphere_scene(&s, LANES_MAT_DIFFUSE, 0, 0.0)) {
        harness_fail("the sphere scene did not build (see above)");
        return;
    }
    /* sphere_scene framed the camera on the sphere: the centre pixel hits it */
    const lanes_kernels *k = lanes_kernels_current();
    lanes_render_accel a;
    lanes_error err;
    if (lanes_render_accel_build(&s, k, false, 0, &a, &err) != LANES_OK) {
        CHECK(false, "%s", err.message);
        lanes_scene_free(&s);
        return;
    }
    lanes_render_options o;
    lanes_render_default_options(&o);
    o.width = o.height = 33;
    lanes_render_result r;
    if (lanes_render(&s, &a, &o, &r, &err) == LANES_OK) {
        const float *c = r.rgb + (16 * 33 + 16) * 3;
        CHECK(c[0] == 0.5f * 0.03f && r.shadow_rays == 0,
              "unlit diffuse sphere: centre pixel %.6g, expected the ambient 0.5 * 0.03; %llu shadow rays",
              c[0], (unsigned long long)r.shadow_rays);
        lanes_render_result_free(&r);
    } else {
        CHECK(false, "%s", err.message);
    }
    o.accuracy = (lanes_accuracy)LANES_ACCURACY_COUNT;
    bool rendered = lanes_render(&s, &a, &o, &r, &err) == LANES_OK;
    CHECK(!rendered && strstr(err.message, "accuracy mode"), "an unknown accuracy mode: %s",
          rendered ? "rendered" : err.message);
    if (rendered) lanes_render_result_free(&r);
    lanes_render_accel_free(&a);
    lanes_scene_free(&s);
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: test_scene_plan DATA_DIR\n");
        return 2;
    }
    decisions();
    recommendation();
    no_geometry_needed();
    far_scene(argv[1]);
    return harness_summary("test_scene_plan");
}
