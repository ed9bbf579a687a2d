/* `lanes paths`: the path tracer (trace/paths.h) on one scene, an image
 * through OpenImageIO and what it measured: rays per second and the
 * shading's SIMD utilisation, as a line or as JSON. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench/cli_commands.h"
#include "bench/cli_common.h"
#include "bench/image_io.h"
#include "build/material_assign.h"
#include "build/parallel.h"
#include "build/scene_load.h"
#include "trace/paths.h"
#include "trace/scene_plan.h"
#ifdef LANES_HAVE_COMPARE
#include "bench/embree_adapter.h"
#endif

static int paths_run(cli_context *ctx, const cli_command *self, int argc, char **argv)
{
    const char *scene_spec = NULL, *out_path = NULL, *value, *method_name = "single", *accuracy_name = NULL;
    const char *assign_name = "cluster", *intersector_name = "lanes", *csv_path = NULL;
    int materials = 0;
    lanes_paths_options o;
    lanes_paths_default_options(&o);
    bool json = false;

    cli_args a = cli_args_begin(ctx, self, argc, argv);
    while (cli_args_next(&a)) {
        if (cli_value(&a, "-o", &out_path) || cli_value(&a, "--output", &out_path)) {
        } else if (cli_value(&a, "--method", &method_name)) {
        } else if (cli_value(&a, "--accuracy", &accuracy_name)) {
        } else if (cli_value(&a, "--spp", &value)) {
            o.spp = (int)cli_parse_count(&a, "--spp", value, 1, LANES_PATHS_MAX_SPP);
        } else if (cli_value(&a, "--depth", &value)) {
            o.depth = (int)cli_parse_count(&a, "--depth", value, 1, LANES_PATHS_MAX_DEPTH);
        } else if (cli_value(&a, "--stream", &value)) {
            o.stream = (int)cli_parse_count(&a, "--stream", value, LANES_PATHS_MIN_STREAM, LANES_PATHS_MAX_STREAM);
            if (o.stream % 16 != 0) cli_usage_error(ctx, self, "--stream %d: a multiple of 16, please", o.stream);
        } else if (cli_value(&a, "--materials", &value)) {
            materials = (int)cli_parse_count(&a, "--materials", value, 1, LANES_ASSIGN_MAX_MATERIALS);
        } else if (cli_value(&a, "--assign", &assign_name)) {
        } else if (cli_value(&a, "--intersector", &intersector_name)) {
        } else if (cli_value(&a, "--csv", &csv_path)) {
        } else if (cli_value(&a, "--threads", &value)) {
            o.threads = (int)cli_parse_count(&a, "--threads", value, 1, 256);
        } else if (cli_value(&a, "--background", &value)) {
            double g = cli_parse_real(&a, "--background", value, 0.0, 1e30);
            o.uniform_background = true;
            o.background[0] = o.background[1] = o.background[2] = (float)g;
        } else if (cli_value(&a, "--size", &value)) {
            cli_parse_size(&a, "--size", value, LANES_CAMERA_MAX_SIDE, &o.width, &o.height);
        } else if (cli_flag(&a, "--json")) {
            json = true;
        } else if (cli_global_option(&a)) {
        } else if (a.argv[a.i][0] != '-' && !scene_spec) {
            scene_spec = a.argv[a.i];
        } else {
            cli_unknown_option(&a);
        }
    }
    int method = lanes_paths_method_from_name(method_name);
    if (method < 0) cli_usage_error(ctx, self, "unknown method '%s' (single, single-1lane, packet, stream)", method_name);
    o.method = (lanes_paths_method)method;
    int accuracy = accuracy_name ? lanes_accuracy_from_name(accuracy_name) : -1;
    if (accuracy_name && accuracy < 0)
        cli_usage_error(ctx, self, "unknown accuracy mode '%s' (fast, default, robust)", accuracy_name);
    o.accuracy = (lanes_accuracy)accuracy;
    int assign = lanes_material_assign_from_name(assign_name);
    if (assign < 0) cli_usage_error(ctx, self, "unknown assignment '%s' (object, cluster, random)", assign_name);
    bool with_embree = strcmp(intersector_name, "embree") == 0;
    if (!with_embree && strcmp(intersector_name, "lanes") != 0)
        cli_usage_error(ctx, self, "unknown intersector '%s' (lanes, embree)", intersector_name);
#ifndef LANES_HAVE_COMPARE
    if (with_embree) cli_fail("paths: --intersector embree: this lanes was built without Embree");
#endif
    if (out_path) cli_make_parent_dirs("paths: -o", out_path);
    /* opened first: a path that cannot be written fails before the render */
    FILE *csv = csv_path ? cli_create_file("paths: --csv", csv_path) : NULL;
    cli_progress_bar bar = cli_progress_bar_make();
    if (!json) o.progress = cli_show_progress, o.progress_ctx = &bar;
    o.isa = lanes_isa_current();
    const lanes_kernels *k = lanes_kernels_for(o.isa);

    lanes_scene scene;
    lanes_error err;
    if (lanes_scene_load(scene_spec, &scene, &err) != LANES_OK) cli_fail("%s", err.message);
    if (materials > 0 && lanes_scene_assign_materials(&scene, materials, (lanes_material_assign)assign, &err) != LANES_OK) {
        lanes_scene_free(&scene);
        cli_fail("%s", err.message);
    }
    lanes_render_accel accel;
    if (lanes_render_accel_build(&scene, k, false, o.threads, &accel, &err) != LANES_OK) {
        lanes_scene_free(&scene);
        cli_fail("%s", err.message);
    }
    lanes_paths_result r;
#ifdef LANES_HAVE_COMPARE
    lanes_embree *embree = NULL;
    lanes_paths_intersector x;
    if (with_embree) {
        if (lanes_embree_create(&scene, lanes_embree_isa_best(), o.threads, &embree, &err) != LANES_OK) {
            lanes_render_accel_free(&accel);
            lanes_scene_free(&scene);
            cli_fail("%s", err.message);
        }
        x = lanes_embree_paths_intersector(embree);
        o.intersector = &x;
    }
#endif
    lanes_status st = lanes_paths_render(&scene, &accel, &o, &r, &err);
    lanes_render_accel_free(&accel);
#ifdef LANES_HAVE_COMPARE
    const char *engine = embree ? lanes_embree_isa_name(lanes_embree_get_isa(embree)) : NULL;
    lanes_embree_destroy(embree);
#else
    const char *engine = NULL;
#endif
    if (st != LANES_OK) {
        lanes_scene_free(&scene);
        cli_fail("%s", err.message);
    }
    if (out_path && lanes_image_write(out_path, r.width, r.height, r.rgb, &err) != LANES_OK) {
        lanes_paths_result_free(&r);
        lanes_scene_free(&scene);
        cli_fail("%s", err.message);
    }
    uint64_t rays = r.shadow_rays;
    for (int d = 0; d <= LANES_PATHS_MAX_DEPTH; d++) rays += r.rays_by_depth[d];
    double mrays = r.seconds > 0.0 ? (double)rays / r.seconds * 1e-6 : 0.0;
    double utilization = r.shade_slots ? (double)r.shade_live / (double)r.shade_slots : 0.0;
    double sampling = r.sample_slots ? (double)r.sample_live / (double)r.sample_slots : 0.0;
    int threads = lanes_parallel_threads(o.threads);
    static const char *const stages[LANES_PATHS_STAGE_COUNT] = {"generate", "intersect", "sort",
                                                               "shade",    "shadow",    "accumulate"};
    if (csv) {
        fprintf(csv, "cpu,scene,method,intersector,isa,lanes,threads,stream,stream_bytes,materials,spp,depth,paths,rays,"
                     "seconds,mrays,shading_utilization");
        for (int i = 0; i < LANES_PATHS_STAGE_COUNT; i++) fprintf(csv, ",%s_seconds", stages[i]);
        fprintf(csv, ",sampling_utilization\n");
        cli_csv_field(csv, lanes_cpu()->brand);
        fputc(',', csv);
        cli_csv_field(csv, scene.name);
        fprintf(csv, ",%s,%s,%s,%d,%d,%d,%zu,%zu,%d,%d,%llu,%llu,%.6f,%.4f,%.4f", lanes_paths_method_name(o.method),
                engine ? "embree" : "lanes", k->name, k->lanes, threads, o.method == LANES_PATHS_STREAM ? o.stream : 0,
                r.stream_bytes, scene.material_count, o.spp, o.depth, (unsigned long long)r.paths, (unsigned long long)rays,
                r.seconds, mrays, utilization);
        for (int i = 0; i < LANES_PATHS_STAGE_COUNT; i++) fprintf(csv, ",%.6f", r.stage_seconds[i]);
        fprintf(csv, ",%.4f\n", sampling);
        cli_finish_file("paths: --csv", csv_path, csv);
    }
    if (json) {
        printf("{\"cpu\": ");
        cli_json_string(stdout, lanes_cpu()->brand);
        printf(", \"rows\": [{\"scene\": ");
        cli_json_string(stdout, scene.name);
        printf(", \"method\": ");
        cli_json_string(stdout, lanes_paths_method_name(o.method));
        printf(", \"isa\": ");
        cli_json_string(stdout, k->name);
        printf(", \"lanes\": %d, \"threads\": %d, \"materials\": %zu, \"spp\": %d, \"depth\": %d, \"paths\": %llu, "
               "\"rays\": %llu, \"seconds\": ",
               k->lanes, threads, scene.material_count, o.spp, o.depth, (unsigned long long)r.paths,
               (unsigned long long)rays);
        cli_json_number(stdout, r.seconds);
        printf(", \"mrays\": ");
        cli_json_number(stdout, mrays);
        printf(", \"shading_utilization\": ");
        cli_json_number(stdout, utilization);
        printf(", \"sampling_utilization\": ");
        cli_json_number(stdout, sampling);
        printf(", \"intersector\": \"%s\"", engine ? "embree" : "lanes");
        if (o.method == LANES_PATHS_STREAM) printf(", \"stream\": %d, \"stream_bytes\": %zu", o.stream, r.stream_bytes);
        if (o.method == LANES_PATHS_STREAM || o.method == LANES_PATHS_PACKET) {
            printf(", \"shading_seconds\": ");
            cli_json_number(stdout, r.stage_seconds[LANES_PATHS_STAGE_SHADE]);
            printf(", \"stage_seconds\": {");
            for (int i = 0; i < LANES_PATHS_STAGE_COUNT; i++) {
                printf("%s\"%s\": ", i ? ", " : "", stages[i]);
                cli_json_number(stdout, r.stage_seconds[i]);
            }
            printf("}");
        }
        printf("}]}\n");
    } else {
        printf("%s: %zu triangles, %zu materials; %dx%d, %d spp, depth %d\n", scene.name, scene.triangle_count,
               scene.material_count, r.width, r.height, o.spp, o.depth);
        printf("method %s, isa %s (%d lanes), %d threads, on %s, built by %s\n", lanes_paths_method_name(o.method),
               k->name, k->lanes, threads, cli_cpu_description(), cli_compiler());
        if (engine)
            printf("intersector: Embree %s (rtcIntersect1M, rtcOccluded1M; one ray: rtcIntersect1, rtcOccluded1), shading by %s\n",
                   engine, k->name);
        printf("rays: %llu (%llu camera, %llu shadow); %.3f s; %.2f Mrays/s; shading utilisation %.3f (the BSDF "
               "sampling calls alone %.3f)\n",
               (unsigned long long)rays, (unsigned long long)r.rays_by_depth[0], (unsigned long long)r.shadow_rays,
               r.seconds, mrays, utilization, sampling);
        if (o.method == LANES_PATHS_STREAM)
            printf("stream of %d paths per thread (%.0f KB)\n", o.stream, (double)r.stream_bytes / 1024.0);
        if (o.method == LANES_PATHS_STREAM || o.method == LANES_PATHS_PACKET)
            printf("thread seconds: generate %.3f, intersect %.3f, sort %.3f, shade %.3f, shadow %.3f, accumulate %.3f\n",
                   r.stage_seconds[0], r.stage_seconds[1], r.stage_seconds[2], r.stage_seconds[3], r.stage_seconds[4],
                   r.stage_seconds[5]);
        if (out_path) printf("wrote %s\n", out_path);
    }
    lanes_paths_result_free(&r);
    lanes_scene_free(&scene);
    return 0;
}

const cli_command cli_cmd_paths = {
    .name = "paths",
    .summary = "path-trace a scene (next-event estimation), with rays per second and shading utilisation",
    .usage = "usage: lanes paths [SCENE] [-o FILE] [options]\n"
             "SCENE: a built-in scene name, a scene file (.json) or a mesh file; default: the\n"
             "embedded default scene\n"
             "  -o, --output FILE     image to write (PNG, EXR, ... as OpenImageIO knows them)\n"
             "  --method M            single (one path at a time, scalar shading; default),\n"
             "                        single-1lane (the set's own shading kernels, one live lane),\n"
             "                        packet (W paths together, each material under its lane mask) or\n"
             "                        stream (per thread a stream of paths sorted by material, shaded\n"
             "                        W at a time; Afra et al. 2016)\n"
             "  --intersector E       lanes (the set's traversal; default) or embree (Embree at its\n"
             "                        best set: rtcIntersect1M and rtcOccluded1M, or the 1-ray calls)\n"
             "  --stream N            stream method: paths in flight per thread, 256..65536, a\n"
             "                        multiple of 16 (default 2048)\n"
             "  --materials N         N generated materials (@mat0000 ...) instead of the scene's own\n"
             "                        (lights keep theirs), 1..65000\n"
             "  --assign A            how: object, cluster (cells of a 64^3 grid; default) or random\n"
             "  --spp N               samples per pixel (default 16)\n"
             "  --depth N             path vertices after the camera, 1..32 (default 8)\n"
             "  --background L        a uniform background of radiance L instead of the sky\n"
             "  --accuracy M          fast, default or robust; default: the scene file's, else default\n"
             "  --size WxH            image size (default: the scene camera's)\n"
             "  --threads N           threads (default: all cores)\n"
             "  --json                the measurements as JSON\n"
             "  --csv FILE            the measurements as a CSV row (with its header)\n"
             "  --isa NAME            instruction set\n",
    .run = paths_run,
};
