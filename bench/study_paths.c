/* `lanes study --paths` (see study_paths.h). Five experiments per scene,
 * each configuration timed reps times (the median kept), interleaved by
 * round so that the machine's load falls on all alike:
 *   methods:   single, single-1lane, packet and stream at each set, the
 *              scene's own materials: Mrays/s, shading utilisation, and
 *              the stream's shading time;
 *   stream:    the stream method's utilisation and speed against the
 *              stream's size, 256 .. 16384 paths, with 36 clustered
 *              materials (the paper's smaller scene);
 *   materials: packet and stream (2048) against the number of clustered
 *              materials, 1 .. 256;
 *   clustered: single, packet and stream with 36 and 111 clustered
 *              materials (the paper's two scenes): Mrays/s and shading
 *              time against packet's, the paper's comparison;
 *   engine:    single and stream with 36 clustered materials again, their
 *              rays traced by Embree (a lanes built with it): the same
 *              paths, lanes' traversal against Embree's;
 *   intersect: the stream's extension rays with 36 clustered materials,
 *              captured and traced again through each intersection call
 *              of lanes and Embree (bench/stream_intersect.h), after the
 *              rounds above.
 * Utilisation does not depend on the run (the paths are the same); time
 * does. */
#include "bench/study_paths.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bench/cli_common.h"
#include "bench/stream_intersect.h"
#include "build/material_assign.h"
#include "build/scene_load.h"
#include "trace/paths.h"
#ifdef LANES_HAVE_COMPARE
#include "bench/embree_adapter.h"
#endif

typedef struct {
    char scene[64], experiment[16];
    lanes_paths_method method;
    lanes_isa isa;
    int lanes, materials, stream, spp;
    bool embree; /* traced by Embree (lanes paths --intersector embree) */
    double mrays[64], utilization, sampling_utilization, shading_seconds[64], intersect_seconds[64], shadow_seconds[64];
} paths_row;

typedef struct {
    paths_row *rows;
    size_t count, capacity;
} paths_rows;

static paths_row *add(paths_rows *l)
{
    if (l->count == l->capacity) {
        size_t cap = l->capacity ? 2 * l->capacity : 64;
        paths_row *r = realloc(l->rows, cap * sizeof *r);
        if (!r) cli_fail("study --paths: out of memory");
        l->rows = r, l->capacity = cap;
    }
    paths_row *r = &l->rows[l->count++];
    memset(r, 0, sizeof *r);
    return r;
}

/* One scene as a configuration renders it: its own materials (0) or n
 * clustered ones; the wide BVH of each width built once. */
typedef struct {
    lanes_scene scene;
    lanes_render_accel accel[17];
#ifdef LANES_HAVE_COMPARE
    lanes_embree *embree; /* at Embree's best set, made when a row asks */
    lanes_paths_intersector intersector;
#endif
} study_scene;

static void scene_open(study_scene *s, const char *spec, int materials)
{
    lanes_error err;
    memset(s, 0, sizeof *s);
    if (lanes_scene_load(spec, &s->scene, &err) != LANES_OK) cli_fail("%s", err.message);
    if (materials > 0 && lanes_scene_assign_materials(&s->scene, materials, LANES_ASSIGN_CLUSTER, &err) != LANES_OK)
        cli_fail("%s", err.message);
}

static const lanes_render_accel *scene_accel(study_scene *s, lanes_isa isa)
{
    const lanes_kernels *k = lanes_kernels_for(isa);
    lanes_render_accel *a = &s->accel[k->wide_width];
    lanes_error err;
    if (a->wide.width == 0 && lanes_render_accel_build(&s->scene, k, false, 0, a, &err) != LANES_OK)
        cli_fail("%s", err.message);
    return a;
}

/* Embree's intersector over the scene, or NULL in a lanes without Embree. */
static const lanes_paths_intersector *scene_embree(study_scene *s)
{
#ifdef LANES_HAVE_COMPARE
    lanes_error err;
    if (!s->embree) {
        if (lanes_embree_create(&s->scene, lanes_embree_isa_best(), 0, &s->embree, &err) != LANES_OK)
            cli_fail("study --paths: %s", err.message);
        s->intersector = lanes_embree_paths_intersector(s->embree);
    }
    return &s->intersector;
#else
    (void)s;
    return NULL;
#endif
}

static void scene_close(study_scene *s)
{
#ifdef LANES_HAVE_COMPARE
    lanes_embree_destroy(s->embree);
#endif
    for (int w = 0; w <= 16; w++)
        if (s->accel[w].wide.width) lanes_render_accel_free(&s->accel[w]);
    lanes_scene_free(&s->scene);
}

static void measure(paths_row *r, study_scene *s, const paths_study_options *o, int round)
{
    lanes_paths_options po;
    lanes_paths_default_options(&po);
    po.isa = r->isa, po.method = r->method, po.spp = r->spp, po.threads = o->threads;
    po.width = o->width, po.height = o->height;
    po.stream = r->stream;
    po.intersector = r->embree ? scene_embree(s) : NULL;
    lanes_paths_result res;
    lanes_error err;
    if (lanes_paths_render(&s->scene, scene_accel(s, r->isa), &po, &res, &err) != LANES_OK)
        cli_fail("study --paths: %s", err.message);
    uint64_t rays = res.shadow_rays;
    for (int d = 0; d <= LANES_PATHS_MAX_DEPTH; d++) rays += res.rays_by_depth[d];
    r->mrays[round] = res.seconds > 0.0 ? (double)rays / res.seconds * 1e-6 : 0.0;
    r->utilization = res.shade_slots ? (double)res.shade_live / (double)res.shade_slots : 0.0;
    r->sampling_utilization = res.sample_slots ? (double)res.sample_live / (double)res.sample_slots : 0.0;
    r->shading_seconds[round] = res.stage_seconds[LANES_PATHS_STAGE_SHADE];
    r->intersect_seconds[round] = res.stage_seconds[LANES_PATHS_STAGE_INTERSECT];
    r->shadow_seconds[round] = res.stage_seconds[LANES_PATHS_STAGE_SHADOW];
    lanes_paths_result_free(&res);
}

static double median(const double *v, int n)
{
    double tmp[64];
    memcpy(tmp, v, (size_t)n * sizeof *tmp);
    return cli_median(tmp, (size_t)n);
}

/* ---- output -------------------------------------------------------------- */

static void write_csv(const char *path, const paths_rows *rows, int reps)
{
    FILE *f = cli_create_file("study --paths", path);
    fprintf(f, "scene,experiment,method,intersector,isa,lanes,materials,stream,spp,mrays,shading_utilization,shading_seconds,"
               "intersect_seconds,shadow_seconds,sampling_utilization\n");
    for (size_t i = 0; i < rows->count; i++) {
        const paths_row *r = &rows->rows[i];
        fprintf(f, "%s,%s,%s,%s,%s,%d,%d,%d,%d,%.4f,%.4f,%.5f,%.5f,%.5f,%.4f\n", r->scene, r->experiment,
                lanes_paths_method_name(r->method), r->embree ? "embree" : "lanes", lanes_isa_name(r->isa), r->lanes,
                r->materials, r->stream, r->spp, median(r->mrays, reps), r->utilization, median(r->shading_seconds, reps),
                median(r->intersect_seconds, reps), median(r->shadow_seconds, reps), r->sampling_utilization);
    }
    cli_finish_file("study --paths", path, f);
}

/* The intersect experiment's results, [scene * nsets + set]. */
typedef struct {
    const stream_intersect_result *at;
    int nsets;
} intersect_results;

static void write_intersect_csv(const char *path, const intersect_results *ir, char scenes[][64], int nscenes,
                                const lanes_isa *sets)
{
    FILE *f = cli_create_file("study --paths", path);
    fprintf(f, "scene,isa,call,engine,rays,streams,mrays,differ\n");
    for (int s = 0; s < nscenes; s++)
        for (int j = 0; j < ir->nsets; j++) {
            const stream_intersect_result *r = &ir->at[s * ir->nsets + j];
            for (int a = 0; a < r->apis; a++)
                fprintf(f, "%s,%s,%s,%s,%zu,%zu,%.4f,%zu\n", scenes[s], lanes_isa_name(sets[j]), r->api[a].name,
                        r->api[a].embree ? "embree" : "lanes", r->rays, r->streams, r->api[a].mrays, r->api[a].differ);
        }
    cli_finish_file("study --paths", path, f);
}

/* The fastest call of one engine, or -1. */
static int best_call(const stream_intersect_result *r, bool embree)
{
    int best = -1;
    for (int a = 0; a < r->apis; a++)
        if (r->api[a].embree == embree && (best < 0 || r->api[a].mrays > r->api[best].mrays)) best = a;
    return best;
}

static void write_intersect_table(FILE *f, const intersect_results *ir, const char *scene, int s, const lanes_isa *sets)
{
    const stream_intersect_result *first = &ir->at[s * ir->nsets];
    fprintf(f, "\n## %s: the intersection stage alone, on the stream's own extension rays (36 clustered materials, "
               "stream 2048, 1 thread)\n\n",
            scene);
    fprintf(f, "%zu rays in %zu trace calls, captured from one stream render per set. Embree's packets take "
               "consecutive rays across the calls; its Np and 1M calls and lanes' take one call per stream. "
               "The lanes/Embree ratio to hold against: `lanes compare %s`'s diffuse rows.\n\n",
            first->rays, first->streams, scene);
    fprintf(f, "| set | call | Mrays/s | vs trace_wide | rays whose hit differs from trace_wide's |\n|---|---|---|---|---|\n");
    for (int j = 0; j < ir->nsets; j++) {
        const stream_intersect_result *r = &ir->at[s * ir->nsets + j];
        double base = r->apis ? r->api[0].mrays : 0.0;
        for (int a = 0; a < r->apis; a++)
            fprintf(f, "| %s | %s | %.2f | %.2f | %zu |\n", lanes_isa_name(sets[j]), r->api[a].name, r->api[a].mrays,
                    base > 0.0 ? r->api[a].mrays / base : 0.0, r->api[a].differ);
    }
    fprintf(f, "\n| set | SoA call / AoS trace_wide | SoA call / AoS set-up + trace_wide | lanes' best | Embree's best (%s) | "
               "lanes / Embree |\n|---|---|---|---|---|---|\n",
            first->embree_isa[0] ? first->embree_isa : "not built");
    for (int j = 0; j < ir->nsets; j++) {
        const stream_intersect_result *r = &ir->at[s * ir->nsets + j];
        int l = best_call(r, false), e = best_call(r, true);
        double soa = r->apis > 2 && r->api[0].mrays > 0.0 ? r->api[1].mrays / r->api[0].mrays : 0.0;
        double soa_setup = r->apis > 2 && r->api[2].mrays > 0.0 ? r->api[1].mrays / r->api[2].mrays : 0.0;
        fprintf(f, "| %s | %.3f | %.3f | %s %.2f |", lanes_isa_name(sets[j]), soa, soa_setup, l >= 0 ? r->api[l].name : "-",
                l >= 0 ? r->api[l].mrays : 0.0);
        if (e >= 0 && l >= 0)
            fprintf(f, " %s %.2f | %.2f |\n", r->api[e].name, r->api[e].mrays,
                    r->api[e].mrays > 0.0 ? r->api[l].mrays / r->api[e].mrays : 0.0);
        else
            fprintf(f, " - | - |\n");
    }
}

static void write_json(const paths_rows *rows, int reps, const char *dir, const intersect_results *ir, char scenes[][64],
                       int nscenes, const lanes_isa *sets)
{
    printf("{\"cpu\": ");
    cli_json_string(stdout, lanes_cpu()->brand);
    printf(", \"out\": ");
    cli_json_string(stdout, dir);
    printf(", \"rows\": [");
    for (size_t i = 0; i < rows->count; i++) {
        const paths_row *r = &rows->rows[i];
        printf("%s{\"scene\": ", i ? ", " : "");
        cli_json_string(stdout, r->scene);
        printf(", \"experiment\": \"%s\", \"method\": \"%s\", \"intersector\": \"%s\", \"isa\": \"%s\", \"lanes\": %d, "
               "\"materials\": %d, \"stream\": %d, \"spp\": %d, \"mrays\": ",
               r->experiment, lanes_paths_method_name(r->method), r->embree ? "embree" : "lanes", lanes_isa_name(r->isa),
               r->lanes, r->materials, r->stream, r->spp);
        cli_json_number(stdout, median(r->mrays, reps));
        printf(", \"shading_utilization\": ");
        cli_json_number(stdout, r->utilization);
        printf(", \"sampling_utilization\": ");
        cli_json_number(stdout, r->sampling_utilization);
        printf(", \"shading_seconds\": ");
        cli_json_number(stdout, median(r->shading_seconds, reps));
        printf(", \"stage_seconds\": {\"intersect\": ");
        cli_json_number(stdout, median(r->intersect_seconds, reps));
        printf(", \"shadow\": ");
        cli_json_number(stdout, median(r->shadow_seconds, reps));
        printf("}");
        printf("}");
    }
    printf("], \"stream_intersect\": [");
    for (int s = 0, n = 0; s < nscenes; s++)
        for (int j = 0; j < ir->nsets; j++) {
            const stream_intersect_result *r = &ir->at[s * ir->nsets + j];
            for (int a = 0; a < r->apis; a++) {
                printf("%s{\"scene\": ", n++ ? ", " : "");
                cli_json_string(stdout, scenes[s]);
                printf(", \"isa\": \"%s\", \"call\": \"%s\", \"engine\": \"%s\", \"rays\": %zu, \"mrays\": ",
                       lanes_isa_name(sets[j]), r->api[a].name, r->api[a].embree ? "embree" : "lanes", r->rays);
                cli_json_number(stdout, r->api[a].mrays);
                printf(", \"differ\": %zu}", r->api[a].differ);
            }
        }
    printf("]}\n");
}

static const paths_row *find(const paths_rows *rows, const char *scene, const char *experiment, lanes_paths_method m,
                             lanes_isa isa, int materials, int stream)
{
    for (size_t i = 0; i < rows->count; i++) {
        const paths_row *r = &rows->rows[i];
        if (strcmp(r->scene, scene) == 0 && strcmp(r->experiment, experiment) == 0 && r->method == m && r->isa == isa &&
            (materials < 0 || r->materials == materials) && (stream < 0 || r->stream == stream))
            return r;
    }
    return NULL;
}

static const int stream_sizes[] = {256, 512, 1024, 2048, 4096, 8192, 16384};
static const int paper_materials[] = {36, 111};
static const int material_counts[] = {1, 4, 16, 64, 256};
enum { NSTREAM = sizeof stream_sizes / sizeof stream_sizes[0], NMAT = sizeof material_counts / sizeof material_counts[0] };

static void write_tables(const char *path, const paths_rows *rows, char scenes[][64], int nscenes, const lanes_isa *sets,
                         int nsets, const paths_study_options *o, const intersect_results *ir)
{
    FILE *f = cli_create_file("study --paths", path);
    fprintf(f, "# Path tracing with shading coherence (Afra et al. 2016)\n\n");
    fprintf(f, "CPU: %s; built by %s; %dx%d, %d spp, %d thread(s), median of %d runs.\n", cli_cpu_description(),
            cli_compiler(), o->width, o->height, o->spp, o->threads, o->reps);
    for (int s = 0; s < nscenes; s++) {
        fprintf(f, "\n## %s: methods (the scene's own materials)\n\n", scenes[s]);
        fprintf(f, "| set | lanes | method | Mrays/s | vs single | shading utilisation |\n|---|---|---|---|---|---|\n");
        for (int j = 0; j < nsets; j++) {
            const paths_row *single = find(rows, scenes[s], "methods", LANES_PATHS_SINGLE, sets[j], -1, -1);
            for (int m = 0; m < LANES_PATHS_METHOD_COUNT; m++) {
                const paths_row *r = find(rows, scenes[s], "methods", (lanes_paths_method)m, sets[j], -1, -1);
                if (!r) continue;
                double mr = median(r->mrays, o->reps), base = single ? median(single->mrays, o->reps) : 0.0;
                fprintf(f, "| %s | %d | %s | %.2f | %.2f | %.3f |\n", lanes_isa_name(sets[j]), r->lanes,
                        lanes_paths_method_name(r->method), mr, base > 0.0 ? mr / base : 0.0, r->utilization);
            }
        }
        fprintf(f, "\n## %s: stream size (36 clustered materials; at least paths / 256 samples per pixel, so that a "
                   "tile's paths fill the stream): shading utilisation / Mrays/s\n\n| paths |", scenes[s]);
        for (int j = 0; j < nsets; j++) fprintf(f, " %s |", lanes_isa_name(sets[j]));
        fprintf(f, "\n|---|");
        for (int j = 0; j < nsets; j++) fprintf(f, "---|");
        fprintf(f, "\n");
        for (int k = 0; k < NSTREAM; k++) {
            fprintf(f, "| %d |", stream_sizes[k]);
            for (int j = 0; j < nsets; j++) {
                const paths_row *r = find(rows, scenes[s], "stream", LANES_PATHS_STREAM, sets[j], -1, stream_sizes[k]);
                if (r) fprintf(f, " %.3f / %.2f |", r->utilization, median(r->mrays, o->reps));
                else fprintf(f, " |");
            }
            fprintf(f, "\n");
        }
        fprintf(f, "\n## %s: the paper's comparison, 36 and 111 clustered materials (stream 2048)\n\n", scenes[s]);
        fprintf(f, "| set | materials | method | Mrays/s | vs packet | vs single | shading utilisation | sampling calls' | shading s | "
                   "packet's shading s / this |\n|---|---|---|---|---|---|---|---|---|---|\n");
        for (int j = 0; j < nsets; j++)
            for (int k = 0; k < 2; k++) {
                const paths_row *single = find(rows, scenes[s], "clustered", LANES_PATHS_SINGLE, sets[j], paper_materials[k], -1);
                const paths_row *packet = find(rows, scenes[s], "clustered", LANES_PATHS_PACKET, sets[j], paper_materials[k], -1);
                for (int m = LANES_PATHS_SINGLE; m <= LANES_PATHS_STREAM; m++) {
                    const paths_row *r = find(rows, scenes[s], "clustered", (lanes_paths_method)m, sets[j], paper_materials[k], -1);
                    if (!r || m == LANES_PATHS_SINGLE_1LANE) continue;
                    double mr = median(r->mrays, o->reps), sh = median(r->shading_seconds, o->reps);
                    double mp = packet ? median(packet->mrays, o->reps) : 0.0, ms = single ? median(single->mrays, o->reps) : 0.0;
                    double sp = packet ? median(packet->shading_seconds, o->reps) : 0.0;
                    fprintf(f, "| %s | %d | %s | %.2f | %.2f | %.2f | %.3f | %.3f |", lanes_isa_name(sets[j]),
                            paper_materials[k], lanes_paths_method_name(r->method), mr, mp > 0.0 ? mr / mp : 0.0,
                            ms > 0.0 ? mr / ms : 0.0, r->utilization, r->sampling_utilization);
                    if (m == LANES_PATHS_SINGLE) fprintf(f, " - | - |\n");
                    else fprintf(f, " %.3f | %.2f |\n", sh, sh > 0.0 ? sp / sh : 0.0);
                }
            }
        if (o->embree) {
            fprintf(f, "\n## %s: the same paths traced by Embree (%s; single: rtcIntersect1 / rtcOccluded1, stream: rtcIntersect1M / "
                       "rtcOccluded1M), 36 clustered "
                       "materials\n\n| set | method | Mrays/s lanes | Mrays/s Embree | lanes / Embree | extension rays s, "
                       "lanes / Embree | shadow rays s, lanes / Embree |\n|---|---|---|---|---|---|---|\n",
                    scenes[s], o->embree_isa);
            for (int j = 0; j < nsets; j++)
                for (int m = LANES_PATHS_SINGLE; m <= LANES_PATHS_STREAM; m += LANES_PATHS_STREAM) {
                    const paths_row *e = find(rows, scenes[s], "engine", (lanes_paths_method)m, sets[j], 36, -1);
                    const paths_row *l = find(rows, scenes[s], "clustered", (lanes_paths_method)m, sets[j], 36, -1);
                    if (!e || !l) continue;
                    double ml = median(l->mrays, o->reps), me = median(e->mrays, o->reps);
                    fprintf(f, "| %s | %s | %.2f | %.2f | %.2f |", lanes_isa_name(sets[j]), lanes_paths_method_name(e->method),
                            ml, me, me > 0.0 ? ml / me : 0.0);
                    if (m == LANES_PATHS_STREAM)
                        fprintf(f, " %.3f / %.3f | %.3f / %.3f |\n", median(l->intersect_seconds, o->reps),
                                median(e->intersect_seconds, o->reps), median(l->shadow_seconds, o->reps),
                                median(e->shadow_seconds, o->reps));
                    else
                        fprintf(f, " - | - |\n");
                }
        }
        write_intersect_table(f, ir, scenes[s], s, sets);
        fprintf(f, "\n## %s: clustered materials: shading utilisation, packet / stream\n\n| materials |", scenes[s]);
        for (int j = 0; j < nsets; j++) fprintf(f, " %s |", lanes_isa_name(sets[j]));
        fprintf(f, "\n|---|");
        for (int j = 0; j < nsets; j++) fprintf(f, "---|");
        fprintf(f, "\n");
        for (int k = 0; k < NMAT; k++) {
            fprintf(f, "| %d |", material_counts[k]);
            for (int j = 0; j < nsets; j++) {
                const paths_row *p = find(rows, scenes[s], "materials", LANES_PATHS_PACKET, sets[j], material_counts[k], -1);
                const paths_row *q = find(rows, scenes[s], "materials", LANES_PATHS_STREAM, sets[j], material_counts[k], -1);
                fprintf(f, " %.3f / %.3f |", p ? p->utilization : 0.0, q ? q->utilization : 0.0);
            }
            fprintf(f, "\n");
        }
    }
    cli_finish_file("study --paths", path, f);
}

/* One data file per plotted line; gnuplot draws them. */
static void write_plots(const char *dir, const paths_rows *rows, const char *scene, const lanes_isa *sets, int nsets)
{
    char path[1200], plot_stream[4096] = "", plot_mat[4096] = "";
    for (int j = 0; j < nsets; j++) {
        const char *isa = lanes_isa_name(sets[j]);
        snprintf(path, sizeof path, "%s/util_stream_%s.dat", dir, isa);
        FILE *f = cli_create_file("study --paths", path);
        for (int k = 0; k < NSTREAM; k++) {
            const paths_row *r = find(rows, scene, "stream", LANES_PATHS_STREAM, sets[j], -1, stream_sizes[k]);
            if (r) fprintf(f, "%d %.4f\n", stream_sizes[k], r->utilization);
        }
        cli_finish_file("study --paths", path, f);
        size_t used = strlen(plot_stream);
        snprintf(plot_stream + used, sizeof plot_stream - used, "%s'util_stream_%s.dat' with linespoints title '%s'",
                 j ? ", " : "", isa, isa);
        for (int m = LANES_PATHS_PACKET; m <= LANES_PATHS_STREAM; m++) {
            const char *method = lanes_paths_method_name((lanes_paths_method)m);
            snprintf(path, sizeof path, "%s/util_materials_%s_%s.dat", dir, method, isa);
            f = cli_create_file("study --paths", path);
            for (int k = 0; k < NMAT; k++) {
                const paths_row *r = find(rows, scene, "materials", (lanes_paths_method)m, sets[j], material_counts[k], -1);
                if (r) fprintf(f, "%d %.4f\n", material_counts[k], r->utilization);
            }
            cli_finish_file("study --paths", path, f);
            used = strlen(plot_mat);
            snprintf(plot_mat + used, sizeof plot_mat - used, "%s'util_materials_%s_%s.dat' with linespoints title '%s %s'",
                     used ? ", " : "", method, isa, method, isa);
        }
    }
    if (system("command -v gnuplot >/dev/null 2>&1") != 0) {
        fprintf(stderr, "study --paths: gnuplot not found (install gnuplot-nox); the data files are written\n");
        return;
    }
    char script[10000];
    snprintf(script, sizeof script,
             "set terminal pngcairo size 900,500\nset grid\nset key outside right\nset logscale x 2\nset yrange [0:1.05]\n"
             "set ylabel 'shading SIMD utilisation'\n"
             "set output 'util_vs_stream.png'\nset xlabel 'paths per stream'\nset title '%s: stream size'\nplot %s\n"
             "set output 'util_vs_materials.png'\nset xlabel 'materials (clustered)'\nset title '%s: materials'\nplot %s\n",
             scene, plot_stream, scene, plot_mat);
    snprintf(path, sizeof path, "%s/paths.gp", dir);
    FILE *f = cli_create_file("study --paths", path);
    fputs(script, f);
    cli_finish_file("study --paths", path, f);
    char cmd[1400];
    snprintf(cmd, sizeof cmd, "cd '%s' && gnuplot paths.gp 2>gnuplot.log", dir);
    if (system(cmd) != 0) fprintf(stderr, "study --paths: gnuplot failed (see %s/gnuplot.log)\n", dir);
}

int lanes_study_paths(const char *const *specs, int nspecs, const lanes_isa *sets, int nsets,
                      const paths_study_options *o)
{
    cli_make_dirs("study --paths", o->out_dir);
    paths_rows rows = {0};
    char scenes[16][64];
    stream_intersect_result *intersect = calloc((size_t)nspecs * (size_t)nsets, sizeof *intersect);
    if (!intersect) cli_fail("study --paths: out of memory");
    intersect_results ir = {intersect, nsets};
    for (int s = 0; s < nspecs; s++) {
        /* the rows of this scene, then their rounds */
        size_t first = rows.count;
        study_scene own, clustered36, clustered111, by_materials[NMAT];
        scene_open(&own, specs[s], 0);
        snprintf(scenes[s], sizeof scenes[s], "%.63s", own.scene.name);
        scene_open(&clustered36, specs[s], 36);
        scene_open(&clustered111, specs[s], 111);
        for (int k = 0; k < NMAT; k++) scene_open(&by_materials[k], specs[s], material_counts[k]);
        for (int j = 0; j < nsets; j++) {
            int lanes = lanes_kernels_for(sets[j])->lanes;
            for (int m = 0; m < LANES_PATHS_METHOD_COUNT; m++) {
                paths_row *r = add(&rows);
                snprintf(r->scene, sizeof r->scene, "%.63s", scenes[s]);
                snprintf(r->experiment, sizeof r->experiment, "methods");
                r->method = (lanes_paths_method)m, r->isa = sets[j], r->lanes = lanes;
                r->materials = (int)own.scene.material_count, r->stream = 2048, r->spp = o->spp;
            }
            for (int k = 0; k < NSTREAM; k++) {
                paths_row *r = add(&rows);
                snprintf(r->scene, sizeof r->scene, "%.63s", scenes[s]);
                snprintf(r->experiment, sizeof r->experiment, "stream");
                r->method = LANES_PATHS_STREAM, r->isa = sets[j], r->lanes = lanes, r->materials = 36;
                r->stream = stream_sizes[k];
                /* a stream fills from one tile's paths: enough samples
                 * that 256 pixels' worth can fill it */
                r->spp = o->spp > stream_sizes[k] / 256 ? o->spp : stream_sizes[k] / 256;
            }
            for (int k = 0; k < NMAT; k++)
                for (int m = LANES_PATHS_PACKET; m <= LANES_PATHS_STREAM; m++) {
                    paths_row *r = add(&rows);
                    snprintf(r->scene, sizeof r->scene, "%.63s", scenes[s]);
                    snprintf(r->experiment, sizeof r->experiment, "materials");
                    r->method = (lanes_paths_method)m, r->isa = sets[j], r->lanes = lanes;
                    r->materials = material_counts[k], r->stream = 2048, r->spp = o->spp;
                }
            for (int m = LANES_PATHS_SINGLE; m <= LANES_PATHS_STREAM && o->embree; m += LANES_PATHS_STREAM) {
                paths_row *r = add(&rows);
                snprintf(r->scene, sizeof r->scene, "%.63s", scenes[s]);
                snprintf(r->experiment, sizeof r->experiment, "engine");
                r->method = (lanes_paths_method)m, r->isa = sets[j], r->lanes = lanes, r->embree = true;
                r->materials = 36, r->stream = 2048, r->spp = o->spp;
            }
            for (int k = 0; k < 2; k++)
                for (int m = LANES_PATHS_SINGLE; m <= LANES_PATHS_STREAM; m++) {
                    if (m == LANES_PATHS_SINGLE_1LANE) continue;
                    paths_row *r = add(&rows);
                    snprintf(r->scene, sizeof r->scene, "%.63s", scenes[s]);
                    snprintf(r->experiment, sizeof r->experiment, "clustered");
                    r->method = (lanes_paths_method)m, r->isa = sets[j], r->lanes = lanes;
                    r->materials = paper_materials[k], r->stream = 2048, r->spp = o->spp;
                }
        }
        size_t total = rows.count - first;
        for (int round = 0; round < o->reps; round++)
            for (size_t i = first; i < rows.count; i++) {
                paths_row *r = &rows.rows[i];
                study_scene *sc = strcmp(r->experiment, "methods") == 0 ? &own
                                  : strcmp(r->experiment, "stream") == 0 ? &clustered36
                                  : strcmp(r->experiment, "engine") == 0    ? &clustered36
                                  : strcmp(r->experiment, "clustered") == 0 ? (r->materials == 36 ? &clustered36 : &clustered111)
                                                                            : NULL;
                for (int k = 0; !sc && k < NMAT; k++)
                    if (material_counts[k] == r->materials) sc = &by_materials[k];
                if (!o->json && isatty(2))
                    fprintf(stderr, "\r%s: %zu of %zu", scenes[s], (size_t)round * total + (i - first) + 1,
                            total * (size_t)o->reps);
                measure(r, sc, o, round);
            }
        if (!o->json && isatty(2)) fprintf(stderr, "\n");
        for (int j = 0; j < nsets; j++) {
            if (!o->json && isatty(2))
                fprintf(stderr, "\r%s: the intersection stage at %s        ", scenes[s], lanes_isa_name(sets[j]));
            lanes_stream_intersect_measure(&clustered36.scene, scene_accel(&clustered36, sets[j]), sets[j], o->width,
                                           o->height, o->spp, 2048, o->reps, (size_t)1 << 22, &intersect[s * nsets + j]);
        }
        if (!o->json && isatty(2)) fprintf(stderr, "\n");
        scene_close(&own);
        scene_close(&clustered36);
        scene_close(&clustered111);
        for (int k = 0; k < NMAT; k++) scene_close(&by_materials[k]);
    }
    char path[1200];
    snprintf(path, sizeof path, "%s/paths.csv", o->out_dir);
    write_csv(path, &rows, o->reps);
    snprintf(path, sizeof path, "%s/tables.md", o->out_dir);
    write_tables(path, &rows, scenes, nspecs, sets, nsets, o, &ir);
    char csv_path[1200];
    snprintf(csv_path, sizeof csv_path, "%s/stream_intersect.csv", o->out_dir);
    write_intersect_csv(csv_path, &ir, scenes, nspecs, sets);
    write_plots(o->out_dir, &rows, scenes[0], sets, nsets);
    if (o->json) {
        write_json(&rows, o->reps, o->out_dir, &ir, scenes, nspecs, sets);
    } else {
        FILE *t = fopen(path, "r");
        char line[1024];
        while (t && fgets(line, sizeof line, t)) fputs(line, stdout);
        if (t) fclose(t);
        printf("\nwrote %s/paths.csv, %s/stream_intersect.csv, %s/tables.md, util_vs_stream.png and "
               "util_vs_materials.png\n",
               o->out_dir, o->out_dir, o->out_dir);
    }
    free(intersect);
    free(rows.rows);
    return 0;
}
