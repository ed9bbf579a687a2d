/* `lanes render`: one image of a scene through any traversal scheme, written
 * by OpenImageIO, with the rays per second it took. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bench/cli_commands.h"
#include "bench/cli_common.h"
#include "bench/image_io.h"
#include "build/scene_load.h"
#include "trace/packet_render.h"
#include "trace/render.h"
#include "trace/scene_plan.h"

static void release_accels(lanes_render_accel *accel, lanes_device device, lanes_accel api_accel)
{
    if (api_accel) {
        lanes_accel_release(api_accel);
        lanes_device_release(device);
    } else {
        lanes_render_accel_free(accel);
    }
}


static int render_run(cli_context *ctx, const cli_command *self, int argc, char **argv)
{
    const char *scene_spec = NULL, *out_path = NULL, *value;
    const char *scheme_name = "wide", *queue_name = "MAX", *accuracy_name = NULL;
    lanes_packet_render_options po;
    lanes_packet_render_default_options(&po);
    bool no_frustum = false, explain = false;

    cli_args a = cli_args_begin(ctx, self, argc, argv);
    while (cli_args_next(&a)) {
        if (cli_value(&a, "-o", &out_path) || cli_value(&a, "--output", &out_path)) {
        } else if (cli_value(&a, "--scheme", &scheme_name)) {
        } else if (cli_value(&a, "--queue", &queue_name)) {
        } else if (cli_value(&a, "--accuracy", &accuracy_name)) {
        } else if (cli_value(&a, "--queue-min", &value)) {
            po.queue_min = (int)cli_parse_count(&a, "--queue-min", value, 1, 1u << 30);
        } else if (cli_value(&a, "--packet", &value)) {
            po.packet_size = (int)cli_parse_count(&a, "--packet", value, 1, LANES_PACKET_MAX_RAYS);
        } else if (cli_value(&a, "--spp", &value)) {
            po.base.spp = (int)cli_parse_count(&a, "--spp", value, 1, 65536);
        } else if (cli_value(&a, "--threads", &value)) {
            po.base.threads = (int)cli_parse_count(&a, "--threads", value, 1, 256);
        } else if (cli_value(&a, "--depth", &value)) {
            po.base.max_depth = (int)cli_parse_count(&a, "--depth", value, 0, LANES_MAX_DEPTH);
        } else if (cli_value(&a, "--size", &value)) {
            cli_parse_size(&a, "--size", value, LANES_CAMERA_MAX_SIDE, &po.base.width, &po.base.height);
        } else if (cli_flag(&a, "--no-frustum")) {
            no_frustum = true;
        } else if (cli_flag(&a, "--explain")) {
            explain = true;
        } else if (cli_flag(&a, "--leaf-frustum")) {
            po.leaf_frustum = true;
        } else if (cli_global_option(&a)) {
        } else if (a.argv[a.i][0] != '-' && !scene_spec) {
            scene_spec = a.argv[a.i];
        } else {
            cli_unknown_option(&a);
        }
    }
    if (!out_path) cli_usage_error(ctx, self, "no output file: give -o FILE (PNG, EXR, ...)");
    cli_make_parent_dirs("render: -o", out_path);

    bool packets = strcmp(scheme_name, "packet") == 0 || strcmp(scheme_name, "ranged") == 0;
    int single_scheme = lanes_scheme_from_name(scheme_name);
    if (!packets && single_scheme < 0)
        cli_usage_error(ctx, self, "unknown scheme '%s' (single, wide, packet, ranged)", scheme_name);
    int queue = lanes_queue_from_name(queue_name);
    if (queue < 0)
        cli_usage_error(ctx, self, "unknown queue heuristic '%s' (MAX, CORNER, none, arrival)", queue_name);
    int accuracy = accuracy_name ? lanes_accuracy_from_name(accuracy_name) : -1;
    if (accuracy_name && accuracy < 0)
        cli_usage_error(ctx, self, "unknown accuracy mode '%s' (fast, default, robust)", accuracy_name);
    po.queue = (lanes_queue_heuristic)queue;
    po.scheme = strcmp(scheme_name, "ranged") == 0 ? LANES_PACKET_RANGED : LANES_PACKET_PARTITION;
    if (no_frustum) po.frustum = po.corner_test = po.leaf_frustum = false;
    po.base.isa = lanes_isa_current();
    const lanes_kernels *k = lanes_kernels_for(po.base.isa);
    int min_packet = lanes_packet_min_size(k->lanes);
    if (packets && (po.packet_size < min_packet || po.packet_size > LANES_PACKET_MAX_RAYS))
        cli_usage_error(ctx, self,
                        "--packet %d out of range (%d..%d at %s: a packet's largest square tile of a "
                        "power-of-two side must hold a whole %d-lane group)",
                        po.packet_size, min_packet, LANES_PACKET_MAX_RAYS, k->name, k->lanes);

    lanes_scene scene;
    lanes_error err;
    if (lanes_scene_load(scene_spec, &scene, &err) != LANES_OK) cli_fail("%s", err.message);
    lanes_scene_plan plan;
    lanes_scene_plan_make(&scene, accuracy, &plan);
    po.base.accuracy = plan.accuracy;
    if (explain) lanes_scene_plan_explain(&plan, stdout);
    if (lanes_scene_plan_check(&plan, &err) != LANES_OK) {
        lanes_scene_free(&scene);
        cli_fail("%s: %s", scene_spec, err.message);
    }
    /* The wide scheme goes through the public API (lanes/lanes.h), as a
     * program linking liblanes would; the others use the internal BVHs. */
    bool use_api = !packets && single_scheme == LANES_SCHEME_WIDE;
    lanes_render_accel accel;
    memset(&accel, 0, sizeof accel);
    lanes_device device = NULL;
    lanes_accel api_accel = NULL;
    uint64_t t0 = cli_now_ns();
    if (use_api) {
        char config[128];
        snprintf(config, sizeof config, "isa=%s,accuracy=%s,threads=%d", k->name,
                 lanes_accuracy_name(plan.accuracy), po.base.threads);
        lanes_status st = lanes_device_create(config, &device);
        if (st == LANES_OK) st = lanes_render_api_accel_create(&scene, device, &api_accel);
        if (st != LANES_OK) {
            lanes_device_release(device);
            lanes_scene_free(&scene);
            const char *msg = lanes_last_error_message();
            cli_fail("%s", msg[0] ? msg : lanes_status_name(st));
        }
        po.base.api_accel = api_accel;
    } else if (lanes_render_accel_build(&scene,
                                        packets || single_scheme == LANES_SCHEME_SINGLE ? NULL : k,
                                        packets || single_scheme == LANES_SCHEME_SINGLE,
                                        po.base.threads, &accel, &err) != LANES_OK) {
        lanes_scene_free(&scene);
        cli_fail("%s", err.message);
    }
    double build_s = (double)(cli_now_ns() - t0) * 1e-9;

    cli_progress_bar bar = cli_progress_bar_make();
    po.base.progress = cli_show_progress;
    po.base.progress_ctx = &bar;
    lanes_render_result r;
    bool ok;
    if (packets) {
        ok = lanes_packet_render(&scene, &accel, &po, &r, NULL, &err) == LANES_OK;
    } else {
        po.base.scheme = (lanes_scheme)single_scheme;
        ok = lanes_render(&scene, &accel, &po.base, &r, &err) == LANES_OK;
    }
    if (!ok) {
        release_accels(&accel, device, api_accel);
        lanes_scene_free(&scene);
        cli_fail("%s", err.message);
    }
    if (lanes_image_write(out_path, r.width, r.height, r.rgb, &err) != LANES_OK) {
        lanes_render_result_free(&r);
        release_accels(&accel, device, api_accel);
        lanes_scene_free(&scene);
        cli_fail("%s", err.message);
    }
    printf("%s: %zu triangles, BVH built in %.3f s\n", scene.name, scene.triangle_count, build_s);
    printf("rendered %dx%d, %d spp, scheme %s", r.width, r.height, po.base.spp, scheme_name);
    if (packets) printf(" (packets of %d, queue %s, queue size %d)", po.packet_size, lanes_queue_name(po.queue), po.queue_min);
    printf(", isa %s (%d lanes), accuracy %s\n", k->name, k->lanes, lanes_accuracy_name(po.base.accuracy));
    printf("rays: %llu camera, %llu shadow, %llu reflected/refracted; %.3f s; %.2f Mrays/s\n",
           (unsigned long long)r.camera_rays, (unsigned long long)r.shadow_rays,
           (unsigned long long)r.secondary_rays, r.seconds,
           r.seconds > 0 ? (double)r.rays / r.seconds * 1e-6 : 0.0);
    printf("wrote %s\n", out_path);
    lanes_render_result_free(&r);
    release_accels(&accel, device, api_accel);
    lanes_scene_free(&scene);
    return 0;
}

const cli_command cli_cmd_render = {
    .name = "render",
    .summary = "render a scene to an image file",
    .usage = "usage: lanes render [SCENE] -o FILE [options]\n"
             "SCENE: a built-in scene name, a scene file (.json) or a mesh file; default: the\n"
             "embedded default scene\n"
             "  -o, --output FILE     image to write (PNG, EXR, ... as OpenImageIO knows them)\n"
             "  --scheme S            single (BVH2), wide (wide BVH, default), packet, ranged\n"
             "  --queue Q             specular packets: MAX (default), CORNER, none (global division,\n"
             "                        rays in no particular order), arrival (global division in the\n"
             "                        order the rays were made)\n"
             "  --queue-min N         queue nodes hold at least N triangles (default 1024)\n"
             "  --packet N            rays per packet, at most 1024 (default 1024)\n"
             "  --no-frustum          packets without frustum culling\n"
             "  --leaf-frustum        rebuild a frustum from the live rays at each leaf (Wu 2.2.3)\n"
             "  --accuracy M          fast, default or robust (see --explain); default: the scene\n"
             "                        file's \"accuracy\", else default\n"
             "  --explain             print what the scene needs (passes, data, accuracy) and why\n"
             "  --spp N               samples per pixel (default 1)\n"
             "  --size WxH            image size (default: the scene camera's)\n"
             "  --depth N             specular bounces (default 10)\n"
             "  --threads N           threads (default: all cores)\n"
             "  --isa NAME            instruction set\n",
    .run = render_run,
};
