/* `lanes study`: the width-scaling study of Wu 2016, chapter 4. Renders each
 * scene with every instruction set this CPU runs, single-ray and packet
 * schemes, queue heuristics and queue sizes; measures render time (medians
 * of repeated runs, counters off) and, in a separate counting run, SIMD
 * utilisation, packet sizes, ray composition and live rays per node. Writes
 * a CSV of every measurement, markdown tables shaped like the thesis'
 * Tables 4.2-4.6 and gnuplot plots into one folder. */
#define _DEFAULT_SOURCE /* mkdir, popen */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "bench/cli_commands.h"
#include "bench/study_paths.h"
#include "bench/cli_common.h"
#ifdef LANES_HAVE_COMPARE
#include "bench/embree_adapter.h"
#include "bench/ray_sets.h"
#endif
#include "build/scene_load.h"
#include "trace/packet_render.h"
#include "trace/render.h"
#include "trace/shading.h"

/* Every scene is studied in one mode, so its rows compare across scenes
 * (a scene file's "accuracy" is for rendering it). */
#define LANES_STUDY_ACCURACY LANES_ACCURACY_DEFAULT

/* One measurement. Rows with rays == "all" carry the render's time; rows
 * per ray type carry that type's counts and utilisation (and the render's
 * time, for reference). NaN where a figure does not apply. */
typedef struct {
    char scene[64];
    char rays[12];
    char scheme[40];
    char isa[16];
    int lanes;
    int node_width;  /* the wide schemes' tree; 0 for the others */
    char family[16]; /* instruction-set family (Embree rows: "embree") */
    int emulated;    /* 1: the width is made of narrower vectors */
    char queue[8];
    int queue_min;
    int packet;
    double util_op, util_packet, seconds, mrays;
    double ray_count, packets, live_node, live_leaf;
    double util_node, util_leaf; /* single rays: filled lanes of node and leaf tests */
} study_row;

typedef struct {
    study_row *rows;
    size_t n, cap;
} row_list;

static study_row *add_row(row_list *l)
{
    if (l->n == l->cap) {
        size_t cap = l->cap ? l->cap * 2 : 256;
        study_row *p = realloc(l->rows, cap * sizeof *p);
        if (!p) cli_fail("study: out of memory");
        l->rows = p;
        l->cap = cap;
    }
    study_row *r = &l->rows[l->n++];
    memset(r, 0, sizeof *r);
    r->util_op = r->util_packet = r->seconds = r->mrays = NAN;
    r->ray_count = r->packets = r->live_node = r->live_leaf = NAN;
    r->util_node = r->util_leaf = NAN;
    return r;
}

typedef struct {
    int reps;
    int width, height;
    int threads;
    int packet;
    const int *queue_sizes;
    int queue_size_count;
    lanes_isa sets[LANES_ISA_COUNT]; /* the sets studied, scalar first, in rising rank */
    int nsets;
    bool quiet;
} study_plan;

static cli_progress progress_bar;

static void progress(const char *what) { cli_progress_step(&progress_bar, what); }

/* Median render time of plan->reps runs with counters off. */
static double timed(const lanes_scene *scene, const lanes_render_accel *accel, bool packets,
                    const lanes_packet_render_options *po, const study_plan *plan, uint64_t *rays)
{
    double t[64];
    int reps = plan->reps < 64 ? plan->reps : 64;
    for (int i = 0; i < reps; i++) {
        lanes_render_result r;
        lanes_error err;
        bool ok = packets ? lanes_packet_render(scene, accel, po, &r, NULL, &err) == LANES_OK
                          : lanes_render(scene, accel, &po->base, &r, &err) == LANES_OK;
        if (!ok) cli_fail("study: %s", err.message);
        t[i] = r.seconds;
        *rays = r.rays;
        lanes_render_result_free(&r);
    }
    return cli_median(t, (size_t)reps);
}

static void fill_common(study_row *r, const lanes_scene *scene, const char *rays, const char *scheme,
                        lanes_isa isa, const char *queue, int queue_min, int packet)
{
    snprintf(r->scene, sizeof r->scene, "%.63s", scene->name);
    snprintf(r->rays, sizeof r->rays, "%s", rays);
    snprintf(r->scheme, sizeof r->scheme, "%s", scheme);
    snprintf(r->isa, sizeof r->isa, "%s", lanes_isa_name(isa));
    r->lanes = lanes_isa_lanes(isa);
    snprintf(r->family, sizeof r->family, "%s", isa == LANES_ISA_NONE ? "embree" : lanes_isa_family(isa));
    r->emulated = lanes_isa_emulated(isa);
    snprintf(r->queue, sizeof r->queue, "%s", queue);
    r->queue_min = queue_min;
    r->packet = packet;
}

/* a / b, NaN when nothing was counted */
static double ratio(uint64_t a, uint64_t b) { return b ? (double)a / (double)b : NAN; }

/* One packet configuration: a timed run and a counting run. */
static void measure_packets(row_list *rows, const lanes_scene *scene, const lanes_render_accel *accel,
                            lanes_isa isa, lanes_packet_scheme scheme, lanes_queue_heuristic queue,
                            int queue_min, const study_plan *plan, FILE *hist)
{
    lanes_packet_render_options po;
    lanes_packet_render_default_options(&po);
    po.base.isa = isa;
    po.base.accuracy = LANES_STUDY_ACCURACY;
    po.base.width = plan->width;
    po.base.height = plan->height;
    po.base.threads = plan->threads;
    po.scheme = scheme;
    po.queue = queue;
    po.queue_min = queue_min;
    po.packet_size = plan->packet;
    const char *scheme_name = scheme == LANES_PACKET_RANGED ? "ranged" : "packet";
    char what[160];
    snprintf(what, sizeof what, "%s: %s at %s, queue %s %d", scene->name, scheme_name, lanes_isa_name(isa),
             lanes_queue_name(queue), queue_min);

    uint64_t rays = 0;
    double seconds = timed(scene, accel, true, &po, plan, &rays);

    static lanes_packet_metrics m; /* large: packet-size histograms */
    lanes_render_result r;
    lanes_error err;
    po.count = true;
    if (lanes_packet_render(scene, accel, &po, &r, &m, &err) != LANES_OK) cli_fail("study: %s", err.message);
    lanes_render_result_free(&r);

    const char *qname = lanes_queue_name(queue);
    study_row *all = add_row(rows);
    fill_common(all, scene, "all", scheme_name, isa, qname, queue_min, plan->packet);
    all->seconds = seconds;
    all->mrays = (double)rays / seconds * 1e-6;
    uint64_t live = 0, slots = 0, packets = 0;
    double util_sum = 0.0, ray_total = 0.0;
    for (int t = 0; t < LANES_RAY_TYPE_COUNT; t++) {
        const lanes_packet_stats *s = &m.stats[t];
        study_row *row = add_row(rows);
        fill_common(row, scene, lanes_ray_type_name((lanes_ray_type)t), scheme_name, isa, qname, queue_min,
                    plan->packet);
        uint64_t tl = s->box_ops.active_lanes + s->tri_ops.active_lanes;
        uint64_t ts = s->box_ops.lane_slots + s->tri_ops.lane_slots;
        row->util_op = ratio(tl, ts);
        row->util_packet = m.packets[t] ? m.packet_util_sum[t] / (double)m.packets[t] : NAN;
        row->seconds = seconds;
        row->mrays = (double)rays / seconds * 1e-6;
        row->ray_count = (double)m.rays[t];
        row->packets = (double)m.packets[t];
        row->live_node = ratio(s->node_live_rays, s->nodes_visited);
        row->live_leaf = ratio(s->leaf_live_rays, s->leaves_visited);
        live += tl;
        slots += ts;
        packets += m.packets[t];
        util_sum += m.packet_util_sum[t];
        ray_total += (double)m.rays[t];
        if (hist && m.packets[t])
            for (int k = 1; k <= LANES_PACKET_MAX_RAYS; k++)
                if (m.packets_of_size[t][k])
                    fprintf(hist, "%s,%s,%s,%s,%s,%d,%d,%llu\n", scene->name, lanes_ray_type_name((lanes_ray_type)t),
                            scheme_name, lanes_isa_name(isa), qname, queue_min, k,
                            (unsigned long long)m.packets_of_size[t][k]);
    }
    all->util_op = ratio(live, slots);
    all->util_packet = packets ? util_sum / (double)packets : NAN;
    all->ray_count = ray_total;
    all->packets = (double)packets;
    progress(what);
}

/* node_width 0: the set's own; else the width sweep's row ("wide-nodes"). */
static void measure_single(row_list *rows, const lanes_scene *scene, const lanes_render_accel *accel,
                           lanes_isa isa, lanes_scheme scheme, int node_width, const study_plan *plan)
{
    lanes_packet_render_options po;
    lanes_packet_render_default_options(&po);
    po.base.isa = isa;
    po.base.accuracy = LANES_STUDY_ACCURACY;
    po.base.scheme = scheme;
    po.base.width = plan->width;
    po.base.height = plan->height;
    po.base.threads = plan->threads;
    po.base.node_width = node_width;
    uint64_t rays = 0;
    double seconds = timed(scene, accel, false, &po, plan, &rays);
    /* then one counting run: how full the node and leaf tests were */
    lanes_render_result counted;
    lanes_error err;
    po.base.count = true;
    if (lanes_render(scene, accel, &po.base, &counted, &err) != LANES_OK) cli_fail("study: %s", err.message);
    const lanes_trace_stats *st = &counted.stats;
    study_row *all = add_row(rows);
    fill_common(all, scene, "all", node_width ? "wide-nodes" : lanes_scheme_name(scheme), isa, "none", 0, 1);
    if (scheme == LANES_SCHEME_WIDE) all->node_width = accel->wide.width;
    all->seconds = seconds;
    all->mrays = (double)rays / seconds * 1e-6;
    all->ray_count = (double)rays;
    all->util_node = ratio(st->node_lanes.active_lanes, st->node_lanes.lane_slots);
    all->util_leaf = ratio(st->leaf_lanes.active_lanes, st->leaf_lanes.lane_slots);
    all->util_op = ratio(st->node_lanes.active_lanes + st->leaf_lanes.active_lanes,
                         st->node_lanes.lane_slots + st->leaf_lanes.lane_slots);
    lanes_render_result_free(&counted);
    char what[160];
    if (scheme == LANES_SCHEME_WIDE)
        snprintf(what, sizeof what, "%s: wide at %s, %d-wide nodes", scene->name, lanes_isa_name(isa),
                 accel->wide.width);
    else
        snprintf(what, sizeof what, "%s: %s at %s", scene->name, lanes_scheme_name(scheme), lanes_isa_name(isa));
    progress(what);
}

#ifdef LANES_HAVE_COMPARE
/* The study's primary rays alone, through lanes' packet traversal at each
 * set and through Embree (rtcIntersect1, and rtcIntersect16 with the
 * coherent flag, its best on such rays), so the JSON carries Embree's rows
 * on the same rays. Rays are pixel centres of the study's camera and size
 * in RAY_ORDER_QUADRANTS (ray_sets.h). Only trace calls are timed;
 * lanes' packet frusta are built inside the clock. */
static void primary_rows(row_list *rows, const lanes_scene *scene, const lanes_bvh2 *bvh,
                         const study_plan *plan)
{
    size_t n = 0;
    lanes_ray *rays = ray_set_camera(scene, plan->width, plan->height, RAY_ORDER_QUADRANTS, &n);
    lanes_rays soa;
    float *tfar0 = malloc((n + 1) * sizeof(float)), *u = malloc((n + LANES_MAX_W) * sizeof(float));
    float *v = malloc((n + LANES_MAX_W) * sizeof(float));
    uint32_t *prim = malloc((n + LANES_MAX_W) * sizeof(uint32_t));
    if (!rays || !tfar0 || !u || !v || !prim || !lanes_rays_alloc(&soa, n)) cli_fail("study: out of memory");
    lanes_error err;
    lanes_embree *e = NULL;
    if (lanes_embree_create(scene, lanes_embree_isa_best(), 0, &e, &err) != LANES_OK)
        cli_fail("study: %s", err.message);
    unsigned csr = lanes_fp_fast_enter();
    double t[64];
    int reps = plan->reps < 64 ? plan->reps : 64;

    for (int j = 0; j < plan->nsets; j++) {
        lanes_isa i = plan->sets[j];
        const lanes_kernels *k = lanes_kernels_for(i);
        for (size_t r = 0; r < n; r++) {
            soa.ox[r] = rays[r].o[0], soa.oy[r] = rays[r].o[1], soa.oz[r] = rays[r].o[2];
            soa.dx[r] = rays[r].d[0], soa.dy[r] = rays[r].d[1], soa.dz[r] = rays[r].d[2];
            soa.tnear[r] = rays[r].tnear, soa.tfar[r] = rays[r].tfar;
        }
        soa.count = n;
        k->rays_prepare(&soa, LANES_RCP_EXACT);
        memcpy(tfar0, soa.tfar, n * sizeof(float));
        for (int rep = 0; rep < reps; rep++) {
            memcpy(soa.tfar, tfar0, n * sizeof(float));
            for (size_t r = 0; r < n; r++) prim[r] = LANES_NO_HIT;
            uint64_t t0 = cli_now_ns();
            for (size_t p = 0; p < n; p += LANES_PACKET_MAX_RAYS) {
                lanes_rays view =
                    lanes_rays_view(&soa, p, n - p < LANES_PACKET_MAX_RAYS ? n - p : LANES_PACKET_MAX_RAYS);
                lanes_frustum f;
                k->frustum_build(&view, NULL, view.count, &f);
                lanes_packet_options po = {LANES_PACKET_PARTITION, LANES_ACCURACY_DEFAULT, &f, true, false, false};
                k->trace_packet(bvh, &po, &view, prim + p, u + p, v + p, NULL, NULL);
            }
            t[rep] = (double)(cli_now_ns() - t0) * 1e-9;
        }
        study_row *row = add_row(rows);
        fill_common(row, scene, "primary", "packet-trace", i, "none", 0, LANES_PACKET_MAX_RAYS);
        row->seconds = cli_median(t, (size_t)reps);
        row->mrays = (double)n / row->seconds * 1e-6;
        row->ray_count = (double)n;
    }
    static const struct {
        lanes_embree_method m;
        bool coherent;
        const char *name;
    } methods[] = {{LANES_EMBREE_1, false, "embree-rtcIntersect1"},
                   {LANES_EMBREE_16, true, "embree-rtcIntersect16-coherent"}};
    for (size_t mi = 0; mi < sizeof methods / sizeof methods[0]; mi++) {
        if (!lanes_embree_supports(e, methods[mi].m)) continue;
        lanes_embree_batch b;
        if (lanes_embree_batch_init(&b, methods[mi].m, false, rays, n, &err) != LANES_OK)
            cli_fail("study: %s", err.message);
        for (int rep = 0; rep < reps; rep++) {
            lanes_embree_batch_reset(&b);
            uint64_t t0 = cli_now_ns();
            lanes_embree_batch_trace(e, &b, 0, n, methods[mi].coherent);
            t[rep] = (double)(cli_now_ns() - t0) * 1e-9;
        }
        lanes_embree_batch_free(&b);
        study_row *row = add_row(rows);
        fill_common(row, scene, "primary", methods[mi].name, LANES_ISA_NONE, "none", 0,
                    lanes_embree_method_width(methods[mi].m));
        snprintf(row->isa, sizeof row->isa, "%s", lanes_embree_isa_name(lanes_embree_get_isa(e)));
        row->lanes = lanes_embree_method_width(methods[mi].m);
        row->seconds = cli_median(t, (size_t)reps);
        row->mrays = (double)n / row->seconds * 1e-6;
        row->ray_count = (double)n;
    }
    lanes_fp_restore(csr);
    lanes_embree_destroy(e);
    lanes_rays_free(&soa);
    free(rays), free(tfar0), free(u), free(v), free(prim);
    char what[256];
    snprintf(what, sizeof what, "%.63s: primary rays, lanes packets and Embree", scene->name);
    progress(what);
}
#endif

/* ---- output ---------------------------------------------------------- */

static void csv_number(FILE *f, double x)
{
    if (isnan(x))
        fputs("", f);
    else
        fprintf(f, "%.6g", x);
}

static void write_csv(const char *path, const row_list *rows)
{
    FILE *f = cli_create_file("study", path);
    fprintf(f, "scene,rays,scheme,isa,lanes,queue,queue_min,packet,util_op,util_packet,seconds,mrays,"
               "ray_count,packets,live_rays_per_node,live_rays_per_leaf,family,emulated,node_width,util_node,"
               "util_leaf\n");
    for (size_t i = 0; i < rows->n; i++) {
        const study_row *r = &rows->rows[i];
        fprintf(f, "%s,%s,%s,%s,%d,%s,%d,%d,", r->scene, r->rays, r->scheme, r->isa, r->lanes, r->queue,
                r->queue_min, r->packet);
        double v[] = {r->util_op, r->util_packet, r->seconds, r->mrays, r->ray_count, r->packets,
                      r->live_node, r->live_leaf};
        for (size_t k = 0; k < sizeof v / sizeof v[0]; k++) {
            if (k) fputc(',', f);
            csv_number(f, v[k]);
        }
        fprintf(f, ",%s,%d,%d,", r->family, r->emulated, r->node_width);
        csv_number(f, r->util_node);
        fputc(',', f);
        csv_number(f, r->util_leaf);
        fputc('\n', f);
    }
    cli_finish_file("study", path, f);
}

static void write_json(FILE *f, const row_list *rows, const char *dir)
{
    fprintf(f, "{\"folder\": ");
    cli_json_string(f, dir);
    fprintf(f, ", \"rows\": [");
    for (size_t i = 0; i < rows->n; i++) {
        const study_row *r = &rows->rows[i];
        fprintf(f, "%s\n  {\"scene\": ", i ? "," : "");
        cli_json_string(f, r->scene);
        fprintf(f, ", \"rays\": \"%s\", \"scheme\": \"%s\", \"isa\": \"%s\", \"lanes\": %d, \"family\": \"%s\", "
                   "\"emulated\": %s, \"queue\": \"%s\", \"queue_min\": %d, \"packet\": %d, \"util_op\": ",
                r->rays, r->scheme, r->isa, r->lanes, r->family, r->emulated ? "true" : "false", r->queue,
                r->queue_min, r->packet);
        cli_json_number(f, r->util_op);
        fprintf(f, ", \"util_packet\": ");
        cli_json_number(f, r->util_packet);
        fprintf(f, ", \"seconds\": ");
        cli_json_number(f, r->seconds);
        fprintf(f, ", \"mrays\": ");
        cli_json_number(f, r->mrays);
        fprintf(f, ", \"node_width\": %d, \"util_node\": ", r->node_width);
        cli_json_number(f, r->util_node);
        fprintf(f, ", \"util_leaf\": ");
        cli_json_number(f, r->util_leaf);
        fprintf(f, "}");
    }
    fprintf(f, "\n]}\n");
}

static const study_row *find(const row_list *rows, const char *scene, const char *rays, const char *scheme,
                             const char *isa, const char *queue, int queue_min)
{
    for (size_t i = 0; i < rows->n; i++) {
        const study_row *r = &rows->rows[i];
        if (strcmp(r->scene, scene) == 0 && strcmp(r->rays, rays) == 0 && strcmp(r->scheme, scheme) == 0 &&
            strcmp(r->isa, isa) == 0 && (!queue || strcmp(r->queue, queue) == 0) &&
            (queue_min < 0 || r->queue_min == queue_min))
            return r;
    }
    return NULL;
}

/* A set's single-ray row on the tree of node width nw: its own width's
 * ("wide") or the sweep's ("wide-nodes"). */
static const study_row *find_nodes(const row_list *rows, const char *scene, const char *isa, int nw)
{
    for (size_t i = 0; i < rows->n; i++) {
        const study_row *r = &rows->rows[i];
        if (strcmp(r->scene, scene) == 0 && strcmp(r->rays, "all") == 0 && strcmp(r->isa, isa) == 0 &&
            (strcmp(r->scheme, "wide") == 0 || strcmp(r->scheme, "wide-nodes") == 0) && r->node_width == nw)
            return r;
    }
    return NULL;
}

/* The fastest packet row of a scene, ISA and queue heuristic over queue sizes. */
static const study_row *best_packet(const row_list *rows, const char *scene, const char *isa, const char *queue)
{
    const study_row *best = NULL;
    for (size_t i = 0; i < rows->n; i++) {
        const study_row *r = &rows->rows[i];
        if (strcmp(r->scene, scene) || strcmp(r->rays, "all") || strcmp(r->scheme, "packet") ||
            strcmp(r->isa, isa) || strcmp(r->queue, queue))
            continue;
        if (!best || r->seconds < best->seconds) best = r;
    }
    return best;
}

static void md_value(FILE *f, double x, const char *fmt)
{
    if (isnan(x))
        fprintf(f, " n/a |");
    else {
        fputc(' ', f);
        fprintf(f, fmt, x);
        fprintf(f, " |");
    }
}

/* The studied sets' families (in the sets' order) and widths (ascending),
 * each once: the rows and columns of the width tables and the plots' series. */
typedef struct {
    const char *families[LANES_ISA_COUNT];
    int nfamilies;
    int widths[LANES_ISA_COUNT];
    int nwidths;
    bool any_emulated;
} set_axes;

static set_axes study_axes(const study_plan *plan)
{
    set_axes a = {.nfamilies = 0};
    for (int j = 0; j < plan->nsets; j++) {
        int w = lanes_isa_lanes(plan->sets[j]);
        const char *fam = lanes_isa_family(plan->sets[j]);
        bool seen_w = false, seen_f = false;
        for (int k = 0; k < a.nwidths; k++) seen_w = seen_w || a.widths[k] == w;
        for (int k = 0; k < a.nfamilies; k++) seen_f = seen_f || strcmp(a.families[k], fam) == 0;
        if (!seen_w) a.widths[a.nwidths++] = w;
        if (!seen_f) a.families[a.nfamilies++] = fam;
        a.any_emulated = a.any_emulated || lanes_isa_emulated(plan->sets[j]);
    }
    for (int i = 1; i < a.nwidths; i++)
        for (int k = i; k > 0 && a.widths[k] < a.widths[k - 1]; k--) {
            int t = a.widths[k];
            a.widths[k] = a.widths[k - 1];
            a.widths[k - 1] = t;
        }
    return a;
}

static void write_tables(const char *path, const row_list *rows, char scenes[][64], int nscenes,
                         const study_plan *plan)
{
    FILE *f = cli_create_file("study", path);
    fprintf(f, "# lanes width-scaling study\n\nCPU: %s; built by %s. Image %dx%d, packets of %d rays, %d thread(s), "
               "accuracy mode %s, median of %d run(s). Times in seconds.\n\n",
            cli_cpu_description(), cli_compiler(), plan->width, plan->height, plan->packet, plan->threads,
            lanes_accuracy_name(LANES_STUDY_ACCURACY), plan->reps);
    const char *queues[] = {"none", "CORNER", "MAX", "arrival"};
    int best_q = plan->queue_size_count ? plan->queue_sizes[0] : 1024;

    fprintf(f, "## Table 4.2: total SIMD utilization (live lanes / lane slots over every SIMD box and triangle "
               "test, all ray types; queue size %d)\n\n"
               "No Queue is the thesis' global division (rays of a direction set in no particular order); "
               "Arrival is global division in the order the rays were made (Hilbert order of the primary packets).\n\n"
               "| Scene | ISA | No Queue | CORNER queue | MAX queue | Arrival |\n|---|---|---|---|---|---|\n", best_q);
    for (int s = 0; s < nscenes; s++)
        for (int j = 0; j < plan->nsets; j++) {
            lanes_isa i = plan->sets[j];
            if (i == LANES_ISA_SCALAR) continue;
            fprintf(f, "| %s | %s |", scenes[s], lanes_isa_name(i));
            for (int q = 0; q < 4; q++) {
                const study_row *r = find(rows, scenes[s], "all", "packet", lanes_isa_name(i), queues[q],
                                          q == 0 || q == 3 ? plan->queue_sizes[0] : best_q);
                md_value(f, r ? r->util_op : NAN, "%.4f");
            }
            fputc('\n', f);
        }
    fprintf(f, "\nThe mean of the per-packet utilization (Def. 4.2.2, every packet weighted alike) is the "
               "util_packet column of measurements.csv; queued tracing makes many small packets, which pulls "
               "that mean down even where the total rises.\n");

    fprintf(f, "\n## Table 4.3: Ray composition (packet scheme, MAX queue)\n\n"
               "| Scene | Primary | Specular | Shadow | Total Rays |\n|---|---|---|---|---|\n");
    for (int s = 0; s < nscenes; s++) {
        const char *isa = lanes_isa_name(plan->sets[plan->nsets - 1]);
        const study_row *p = find(rows, scenes[s], "primary", "packet", isa, "MAX", best_q);
        const study_row *sp = find(rows, scenes[s], "specular", "packet", isa, "MAX", best_q);
        const study_row *sh = find(rows, scenes[s], "shadow", "packet", isa, "MAX", best_q);
        if (!p || !sp || !sh) continue;
        double total = p->ray_count + sp->ray_count + sh->ray_count;
        fprintf(f, "| %s | %.2f%% | %.2f%% | %.2f%% | %.0f |\n", scenes[s], 100 * p->ray_count / total,
                100 * sp->ray_count / total, 100 * sh->ray_count / total, total);
    }

    fprintf(f, "\n## Table 4.4: Single ray rendering times (scalar, BVH2)\n\n| Scene | Time |\n|---|---|\n");
    for (int s = 0; s < nscenes; s++) {
        const study_row *r = find(rows, scenes[s], "all", "single", "scalar", NULL, -1);
        fprintf(f, "| %s |", scenes[s]);
        md_value(f, r ? r->seconds : NAN, "%.3f");
        fputc('\n', f);
    }

    fprintf(f, "\n## Table 4.5: SIMD rendering times (packets; best over queue sizes, size in brackets)\n\n"
               "| Scene |");
    for (int j = 0; j < plan->nsets; j++)
        fprintf(f, " %s |", plan->sets[j] == LANES_ISA_SCALAR ? "Single (scalar packets)" : lanes_isa_name(plan->sets[j]));
    fprintf(f, "\n|---|");
    for (int j = 0; j < plan->nsets; j++) fprintf(f, "---|");
    fputc('\n', f);
    for (int s = 0; s < nscenes; s++)
        for (int q = 0; q < 3; q++) {
            fprintf(f, "| %s%s%s |", scenes[s], q ? " " : "", q ? queues[q] : "");
            for (int j = 0; j < plan->nsets; j++) {
                const study_row *r = best_packet(rows, scenes[s], lanes_isa_name(plan->sets[j]), queues[q]);
                if (r && q)
                    fprintf(f, " %.3f (%d) |", r->seconds, r->queue_min);
                else
                    md_value(f, r ? r->seconds : NAN, "%.3f");
            }
            fputc('\n', f);
        }

    fprintf(f, "\n## Table 4.6: SIMD speedup\n\nS v X: single-ray scalar BVH2 time / packet time at X. "
               "P v X: scalar packet time / packet time at X. W v X: single-ray scalar BVH2 / single-ray wide BVH at X.\n\n"
               "| Scene |");
    for (int j = 0; j < plan->nsets; j++) {
        const char *name = lanes_isa_name(plan->sets[j]);
        if (plan->sets[j] != LANES_ISA_SCALAR) fprintf(f, " S v %s | P v %s | W v %s |", name, name, name);
    }
    fprintf(f, "\n|---|");
    for (int j = 0; j < plan->nsets; j++)
        if (plan->sets[j] != LANES_ISA_SCALAR) fprintf(f, "---|---|---|");
    fputc('\n', f);
    for (int s = 0; s < nscenes; s++)
        for (int q = 0; q < 3; q++) {
            const study_row *single = find(rows, scenes[s], "all", "single", "scalar", NULL, -1);
            const study_row *scalar_p = best_packet(rows, scenes[s], "scalar", queues[q]);
            fprintf(f, "| %s%s%s |", scenes[s], q ? " " : "", q ? queues[q] : "");
            for (int j = 0; j < plan->nsets; j++) {
                lanes_isa i = plan->sets[j];
                if (i == LANES_ISA_SCALAR) continue;
                const study_row *p = best_packet(rows, scenes[s], lanes_isa_name(i), queues[q]);
                const study_row *w = find(rows, scenes[s], "all", "wide", lanes_isa_name(i), NULL, -1);
                md_value(f, single && p ? single->seconds / p->seconds : NAN, "%.2f");
                md_value(f, scalar_p && p ? scalar_p->seconds / p->seconds : NAN, "%.2f");
                md_value(f, single && w ? single->seconds / w->seconds : NAN, "%.2f");
            }
            fputc('\n', f);
        }

    fprintf(f, "\n## Primary rays alone: lanes packets against Embree on the same rays\n\n"
               "Trace calls only (lanes: packets of 1024 rays, 32x32 pixels, frustum built inside the clock; "
               "Embree: rtcIntersect1, and rtcIntersect16 with the coherent flag on 4x4 tiles).\n\n"
               "| Scene | method | isa | Mrays/s |\n|---|---|---|---|\n");
    for (size_t i = 0; i < rows->n; i++) {
        const study_row *r = &rows->rows[i];
        if (strcmp(r->rays, "primary") || (strcmp(r->scheme, "packet-trace") && strncmp(r->scheme, "embree-", 7)))
            continue;
        fprintf(f, "| %s | %s | %s | %.2f |\n", r->scene, r->scheme, r->isa, r->mrays);
    }

    /* Width against instruction set: the sets of one family at each width. */
    const set_axes axes = study_axes(plan);
    const int *widths = axes.widths, nwidths = axes.nwidths, nfamilies = axes.nfamilies;
    const char *const *families = axes.families;
    fprintf(f, "\n## Width against instruction set (render seconds: packets with the MAX queue / single ray on "
               "the wide BVH)\n\nOne row per instruction-set family: along a row the width changes and the "
               "instruction set stays; down a column the instruction set changes and the width stays. "
               "* marks a width emulated with narrower vectors.\n\n| Scene | family |");
    for (int k = 0; k < nwidths; k++) fprintf(f, " %d lane%s |", widths[k], widths[k] == 1 ? "" : "s");
    fprintf(f, "\n|---|---|");
    for (int k = 0; k < nwidths; k++) fprintf(f, "---|");
    fputc('\n', f);
    for (int s = 0; s < nscenes; s++)
        for (int k = 0; k < nfamilies; k++) {
            fprintf(f, "| %s | %s |", scenes[s], families[k]);
            for (int w = 0; w < nwidths; w++) {
                lanes_isa isa = LANES_ISA_NONE;
                for (int j = 0; j < plan->nsets; j++)
                    if (lanes_isa_lanes(plan->sets[j]) == widths[w] && strcmp(lanes_isa_family(plan->sets[j]), families[k]) == 0)
                        isa = plan->sets[j];
                const study_row *p = isa == LANES_ISA_NONE ? NULL : best_packet(rows, scenes[s], lanes_isa_name(isa), "MAX");
                const study_row *wd = isa == LANES_ISA_NONE ? NULL : find(rows, scenes[s], "all", "wide", lanes_isa_name(isa), NULL, -1);
                if (!p || !wd)
                    fprintf(f, " |");
                else
                    fprintf(f, " %.3f / %.3f (%s%s) |", p->seconds, wd->seconds, lanes_isa_name(isa),
                            lanes_isa_emulated(isa) ? "*" : "");
            }
            fputc('\n', f);
        }

    fprintf(f, "\n## Live rays per visited node (Bikker 2012, Table 2 measure; packet scheme, MAX queue %d)\n\n"
               "| Scene | ISA | Rays | Interior | Leaf |\n|---|---|---|---|---|\n", best_q);
    for (int s = 0; s < nscenes; s++)
        for (int j = 0; j < plan->nsets; j++) {
            lanes_isa i = plan->sets[j];
            for (int t = 0; t < LANES_RAY_TYPE_COUNT; t++) {
                const study_row *r = find(rows, scenes[s], lanes_ray_type_name((lanes_ray_type)t), "packet",
                                          lanes_isa_name(i), "MAX", best_q);
                if (!r || isnan(r->live_node)) continue;
                fprintf(f, "| %s | %s | %s | %.1f | %.1f |\n", scenes[s], lanes_isa_name(i), r->rays,
                        r->live_node, r->live_leaf);
            }
        }

    fprintf(f, "\n## Node width: single rays through the wide BVH (all ray types), Mrays/s\n\n"
               "Every set traverses the trees of every node width from its lane count up, a node's children "
               "in width / lanes vectors; * marks the set's own width, its default. In parentheses, the SIMD "
               "utilisation of its node tests / leaf tests: lanes holding a real child or triangle over lane "
               "slots, from one counting run over the same rays. The last column is 16 "
               "lanes over 8 of the same instruction family on the same 16-wide tree.\n\n"
               "| Scene | ISA | 4-wide | 8-wide | 16-wide | 16 lanes / 8 (16-wide) |\n|---|---|---|---|---|---|\n");
    for (int s = 0; s < nscenes; s++)
        for (int j = 0; j < plan->nsets; j++) {
            lanes_isa i = plan->sets[j];
            const lanes_kernels *own = lanes_kernels_for(i);
            fprintf(f, "| %s | %s |", scenes[s], lanes_isa_name(i));
            for (int nw = 4; nw <= 16; nw *= 2) {
                const study_row *r = find_nodes(rows, scenes[s], lanes_isa_name(i), nw);
                if (r)
                    fprintf(f, " %.3f%s (%.0f%% / %.0f%%) |", r->mrays, nw == own->wide_width ? "*" : "",
                            100 * r->util_node, 100 * r->util_leaf);
                else
                    fprintf(f, " |");
            }
            /* the 8-lane set of the same family: avx512 over avx512vl8, avx512emu over avx2 */
            const char *half = i == LANES_ISA_AVX512 ? "avx512vl8" : i == LANES_ISA_AVX512EMU ? "avx2" : NULL;
            const study_row *r16 = find_nodes(rows, scenes[s], lanes_isa_name(i), 16);
            const study_row *r8 = half ? find_nodes(rows, scenes[s], half, 16) : NULL;
            if (r16 && r8)
                fprintf(f, " %.2f (over %s) |\n", r16->mrays / r8->mrays, half);
            else
                fprintf(f, " |\n");
        }
    cli_finish_file("study", path, f);
}

/* gnuplot scripts read the CSV files; a missing gnuplot is reported, not
 * hidden, and a script that cannot be written is a write failure like any
 * other output's. */
static bool run_gnuplot(const char *dir, const char *script_name, const char *script)
{
    char path[2400], cmd[5000];
    snprintf(path, sizeof path, "%s/%s", dir, script_name);
    FILE *f = cli_create_file("study", path);
    fputs(script, f);
    cli_finish_file("study", path, f);
    snprintf(cmd, sizeof cmd, "cd '%s' && gnuplot '%s' 2>gnuplot.log", dir, script_name);
    return system(cmd) == 0;
}

static void write_plots(const char *dir, const row_list *rows, char scenes[][64], int nscenes,
                        const study_plan *plan, FILE *report)
{
    if (system("command -v gnuplot >/dev/null 2>&1") != 0) {
        fprintf(report, "plots: gnuplot not found (install gnuplot-nox); CSV files are written\n");
        return;
    }
    char script[16384];
    for (int s = 0; s < nscenes; s++) {
        const char *sc = scenes[s];
        /* utilisation vs lanes per ray type, MAX queue at the first queue
         * size: one point per width (the first set of that width: the sets
         * of one width run one algorithm and differ only in rounding;
         * tables.md has each one) */
        snprintf(script, sizeof script,
                 "set datafile separator ','\nset terminal pngcairo size 800,500\n"
                 "set output 'util_vs_lanes_%s.png'\nset title 'SIMD utilization vs lanes: %s (packets, MAX queue %d)'\n"
                 "set xlabel 'lanes'\nset ylabel 'SIMD utilization (live lanes / lane slots)'\nset yrange [0:1.05]\nset logscale x 2\n"
                 "set key bottom left\n"
                 "f(t)=sprintf(\"< awk -F, '$1==\\\"%s\\\" && $2==\\\"%%s\\\" && $3==\\\"packet\\\" && $6==\\\"MAX\\\" && $7==%d && !seen[$5]++' measurements.csv | sort -t, -k5n\", t)\n"
                 "plot for [t in 'primary shadow specular all'] f(t) using 5:9 with linespoints title t\n",
                 sc, sc, plan->queue_sizes[0], sc, plan->queue_sizes[0]);
        char name[1200];
        snprintf(name, sizeof name, "util_vs_lanes_%s.gp", sc);
        if (!run_gnuplot(dir, name, script)) fprintf(report, "plots: gnuplot failed on %s (see gnuplot.log)\n", name);

        /* speedup over the scalar single-ray BVH2 vs lanes: one panel per
         * method, one series per instruction-set family (x = lanes), so
         * the width's effect reads along a series and the instruction
         * set's across series at one x; emulated widths ringed */
        int used = snprintf(script, sizeof script,
                            "set datafile separator ','\nset terminal pngcairo size 1500,560\n"
                            "set output 'speedup_vs_lanes_%s.png'\n"
                            "set multiplot layout 1,3 title 'Speedup over scalar single-ray: %s (one series per instruction-set family)'\n"
                            "set xlabel 'lanes'\nset ylabel 'speedup'\nset logscale x 2\nset xrange [0.8:20]\nset yrange [0:*]\n"
                            "set key below horizontal maxcols 3\n"
                            "base=system(\"awk -F, '$1==\\\"%s\\\" && $2==\\\"all\\\" && $3==\\\"single\\\" && $4==\\\"scalar\\\" {print $11}' measurements.csv\")+0\n"
                            "f(s,q,fam,emu)=sprintf(\"< awk -F, '$1==\\\"%s\\\" && $2==\\\"all\\\" && $3==\\\"%%s\\\" && ($6==\\\"%%s\\\") && ($7==%d || $7==0) && $17==\\\"%%s\\\" && $18 >= %%d' measurements.csv | sort -t, -k5n\", s, q, fam, emu)\n",
                            sc, sc, sc, sc, plan->queue_sizes[0]);
        static const char *const methods[][3] = {{"packet", "MAX", "packets (MAX queue)"},
                                                 {"ranged", "MAX", "ranged packets"},
                                                 {"wide", "none", "single ray, wide BVH"}};
        const set_axes axes = study_axes(plan);
        const char *const *families = axes.families;
        const int nfamilies = axes.nfamilies;
        const bool any_emulated = axes.any_emulated;
        for (int m = 0; m < 3 && used > 0 && (size_t)used < sizeof script; m++) {
            used += snprintf(script + used, sizeof script - (size_t)used, "set title '%s'\nplot ", methods[m][2]);
            for (int k = 0; k < nfamilies && used > 0 && (size_t)used < sizeof script; k++)
                used += snprintf(script + used, sizeof script - (size_t)used,
                                 "%sf('%s','%s','%s',0) using 5:(base/$11) with linespoints lw 2 title '%s'",
                                 k ? ", " : "", methods[m][0], methods[m][1], families[k], families[k]);
            for (int k = 0; any_emulated && k < nfamilies && used > 0 && (size_t)used < sizeof script; k++) {
                bool has = false;
                for (int j = 0; j < plan->nsets; j++)
                    has = has || (lanes_isa_emulated(plan->sets[j]) && strcmp(lanes_isa_family(plan->sets[j]), families[k]) == 0);
                if (has)
                    used += snprintf(script + used, sizeof script - (size_t)used,
                                     ", f('%s','%s','%s',1) using 5:(base/$11) with points pt 6 ps 3 lc rgb 'black' title '%s: emulated width'",
                                     methods[m][0], methods[m][1], families[k], families[k]);
            }
            if (used > 0 && (size_t)used < sizeof script) used += snprintf(script + used, sizeof script - (size_t)used, "\n");
        }
        if (used > 0 && (size_t)used < sizeof script) snprintf(script + used, sizeof script - (size_t)used, "unset multiplot\n");
        snprintf(name, sizeof name, "speedup_vs_lanes_%s.gp", sc);
        if (!run_gnuplot(dir, name, script)) fprintf(report, "plots: gnuplot failed on %s (see gnuplot.log)\n", name);

        /* packet size histograms per ray type at the widest native set;
         * only the ray types the scene has (gnuplot fails on empty data) */
        const char *isa = NULL;
        for (int j = plan->nsets - 1; j >= 0 && !isa; j--)
            if (!lanes_isa_emulated(plan->sets[j])) isa = lanes_isa_name(plan->sets[j]);
        const char *types[LANES_RAY_TYPE_COUNT];
        int ntypes = 0;
        for (int t = 0; t < LANES_RAY_TYPE_COUNT; t++) {
            const study_row *r = find(rows, sc, lanes_ray_type_name((lanes_ray_type)t), "packet", isa, "MAX",
                                      plan->queue_sizes[0]);
            if (r && r->ray_count > 0) types[ntypes++] = lanes_ray_type_name((lanes_ray_type)t);
        }
        if (ntypes > 0) {
            used = snprintf(script, sizeof script,
                                "set datafile separator ','\nset terminal pngcairo size %d,400\n"
                                "set output 'packet_sizes_%s.png'\nset multiplot layout 1,%d title 'Rays per packet: %s (%s, MAX queue %d)'\n"
                                "set style fill solid\nset xlabel 'rays in packet'\nset ylabel 'packets'\nset xrange [0:%d]\n"
                                "f(t)=sprintf(\"< awk -F, '$1==\\\"%s\\\" && $2==\\\"%%s\\\" && $3==\\\"packet\\\" && $4==\\\"%s\\\" && $5==\\\"MAX\\\" && $6==%d' histograms.csv\", t)\n",
                                400 * ntypes, sc, ntypes, sc, isa, plan->queue_sizes[0], plan->packet + 8, sc, isa,
                                plan->queue_sizes[0]);
            for (int t = 0; t < ntypes && used > 0 && (size_t)used < sizeof script; t++)
                used += snprintf(script + used, sizeof script - (size_t)used,
                                 "set title '%s'\nplot f('%s') using 7:8 with impulses notitle\n", types[t], types[t]);
            if (used > 0 && (size_t)used < sizeof script)
                snprintf(script + used, sizeof script - (size_t)used, "unset multiplot\n");
            snprintf(name, sizeof name, "packet_sizes_%s.gp", sc);
            if (!run_gnuplot(dir, name, script)) fprintf(report, "plots: gnuplot failed on %s (see gnuplot.log)\n", name);
        }

        if (plan->queue_size_count > 1) {
            /* utilisation and time vs queue size (Figs. 4.6, 4.19) */
            snprintf(script, sizeof script,
                     "set datafile separator ','\nset terminal pngcairo size 1100,450\n"
                     "set output 'queue_size_%s.png'\nset multiplot layout 1,2 title 'Queue size: %s (%s)'\n"
                     "set logscale x 2\nset xlabel 'minimum triangles in a queue node'\nset key bottom left\n"
                     "f(q)=sprintf(\"< awk -F, '$1==\\\"%s\\\" && $2==\\\"specular\\\" && $3==\\\"packet\\\" && $4==\\\"%s\\\" && $6==\\\"%%s\\\"' measurements.csv | sort -t, -k7n\", q)\n"
                     "set ylabel 'specular SIMD utilization (total)'\nplot f('MAX') using 7:9 with linespoints title 'MAX', f('CORNER') using 7:9 with linespoints title 'CORNER'\n"
                     "set ylabel 'render time (s)'\nplot f('MAX') using 7:11 with linespoints title 'MAX', f('CORNER') using 7:11 with linespoints title 'CORNER'\n"
                     "unset multiplot\n",
                     sc, sc, isa, sc, isa);
            snprintf(name, sizeof name, "queue_size_%s.gp", sc);
            if (!run_gnuplot(dir, name, script)) fprintf(report, "plots: gnuplot failed on %s (see gnuplot.log)\n", name);
        }
    }
}

static int study_run(cli_context *ctx, const cli_command *self, int argc, char **argv)
{
    const char *out_dir = NULL, *value;
    bool full = false, json = false, paths = false;
    const char *scene_specs[16];
    int nspecs = 0;
    study_plan plan = {.reps = 3, .width = 256, .height = 256, .threads = 1, .packet = LANES_PACKET_MAX_RAYS};
    static const int quick_sizes[] = {1024};
    static const int full_sizes[] = {256, 1024, 4096, 16384};
    plan.queue_sizes = quick_sizes;
    plan.queue_size_count = 1;
    bool size_given = false, reps_given = false;

    cli_args a = cli_args_begin(ctx, self, argc, argv);
    while (cli_args_next(&a)) {
        if (cli_flag(&a, "--full")) {
            full = true;
        } else if (cli_flag(&a, "--paths")) {
            paths = true;
        } else if (cli_flag(&a, "--json")) {
            json = true;
        } else if (cli_value(&a, "--out", &out_dir)) {
        } else if (cli_value(&a, "--reps", &value)) {
            plan.reps = (int)cli_parse_count(&a, "--reps", value, 1, 64);
            reps_given = true;
        } else if (cli_value(&a, "--threads", &value)) {
            plan.threads = (int)cli_parse_count(&a, "--threads", value, 1, 256);
        } else if (cli_value(&a, "--packet", &value)) {
            plan.packet = (int)cli_parse_count(&a, "--packet", value, 16, LANES_PACKET_MAX_RAYS);
        } else if (cli_value(&a, "--size", &value)) {
            cli_parse_size(&a, "--size", value, 8192, &plan.width, &plan.height);
            size_given = true;
        } else if (cli_global_option(&a)) {
        } else if (a.argv[a.i][0] != '-') {
            if (nspecs == 16) cli_usage_error(ctx, self, "at most 16 scenes");
            scene_specs[nspecs++] = a.argv[a.i];
        } else {
            cli_unknown_option(&a);
        }
    }
    if (paths) {
        /* the path tracer's study: every set but scalar (whose shading
         * the single method uses anyway), scalar alone where it is all */
        lanes_isa sets[LANES_ISA_COUNT];
        int nsets = 0;
        const lanes_isa *order = lanes_isa_ranked();
        for (int i = LANES_ISA_COUNT - 1; i >= 0; i--)
            if (lanes_isa_supported(order[i]) && order[i] != LANES_ISA_SCALAR &&
                (ctx->forced_isa == LANES_ISA_NONE || order[i] == ctx->forced_isa))
                sets[nsets++] = order[i];
        if (nsets == 0) sets[nsets++] = LANES_ISA_SCALAR;
        if (nspecs == 0) scene_specs[nspecs++] = full ? "sponza-bunny" : "default";
        paths_study_options po = {out_dir ? out_dir : "out/paths", size_given ? plan.width : (full ? 256 : 128),
                                  size_given ? plan.height : (full ? 256 : 128), full ? 16 : 8,
                                  reps_given ? plan.reps : (full ? 5 : 3), plan.threads, json, false, NULL};
#ifdef LANES_HAVE_COMPARE
        po.embree = true;
        po.embree_isa = lanes_embree_isa_name(lanes_embree_isa_best());
#endif
        return lanes_study_paths(scene_specs, nspecs, sets, nsets, &po);
    }
    if (!out_dir) out_dir = "out/study";
    if (full) {
        plan.queue_sizes = full_sizes;
        plan.queue_size_count = 4;
        if (!size_given) plan.width = plan.height = 512; /* the thesis' image size */
        if (!reps_given) plan.reps = 5;
        if (nspecs == 0) {
            scene_specs[nspecs++] = "dragon";
            scene_specs[nspecs++] = "sponza-bunny";
            scene_specs[nspecs++] = "20-bunnies";
            scene_specs[nspecs++] = "hairball";
        }
    }
    if (nspecs == 0) scene_specs[nspecs++] = "default";
    /* Every set this CPU runs, scalar first, in rising rank (a width's
     * sets side by side); --isa narrows it to scalar (the baseline) plus
     * that set. */
    const lanes_isa *ranked = lanes_isa_ranked();
    for (int i = LANES_ISA_COUNT - 1; i >= 0; i--) {
        lanes_isa isa = ranked[i];
        if (lanes_isa_supported(isa) &&
            (ctx->forced_isa == LANES_ISA_NONE || isa == ctx->forced_isa || isa == LANES_ISA_SCALAR))
            plan.sets[plan.nsets++] = isa;
    }
    cli_make_dirs("study", out_dir);

    int nisa = plan.nsets;
    /* per scene: single scalar + wide per ISA + ranged per ISA + packet none + packet MAX/CORNER per size */
    int node_sweep = 0; /* the other node widths each set traverses */
    for (int j = 0; j < nisa; j++)
        for (int nw = 4; nw <= 16; nw *= 2)
            node_sweep += nw != lanes_kernels_for(plan.sets[j])->wide_width && lanes_kernels_for_width(plan.sets[j], nw);
    progress_bar.total = nspecs * (1 + nisa + node_sweep + nisa + nisa * (2 + 2 * plan.queue_size_count));
#ifdef LANES_HAVE_COMPARE
    progress_bar.total += nspecs;
#endif

    char hist_path[1024];
    snprintf(hist_path, sizeof hist_path, "%s/histograms.csv", out_dir);
    FILE *hist = cli_create_file("study", hist_path);
    fprintf(hist, "scene,rays,scheme,isa,queue,queue_min,rays_in_packet,packets\n");

    row_list rows = {0};
    char scenes[16][64];
    for (int s = 0; s < nspecs; s++) {
        lanes_scene scene;
        lanes_error err;
        if (lanes_scene_load(scene_specs[s], &scene, &err) != LANES_OK) cli_fail("%s", err.message);
        snprintf(scenes[s], sizeof scenes[s], "%.63s", scene.name);
        lanes_render_accel accel4 = {0}, accel8 = {0}, accel16 = {0};
        lanes_render_accel *by_width[17] = {0};
        /* the BVH2 (single ray, packets) is shared; each wide width gets its
         * own build */
        if (lanes_render_accel_build(&scene, NULL, true, 0, &accel4, &err) != LANES_OK) cli_fail("%s", err.message);
        accel8.bvh2 = accel4.bvh2;
        accel16.bvh2 = accel4.bvh2;
        if (lanes_wbvh_build(&scene, 4, NULL, &accel4.wide, &err) != LANES_OK ||
            lanes_wbvh_build(&scene, 8, NULL, &accel8.wide, &err) != LANES_OK ||
            lanes_wbvh_build(&scene, 16, NULL, &accel16.wide, &err) != LANES_OK)
            cli_fail("%s", err.message);
        by_width[4] = &accel4, by_width[8] = &accel8, by_width[16] = &accel16;

        measure_single(&rows, &scene, &accel4, LANES_ISA_SCALAR, LANES_SCHEME_SINGLE, 0, &plan);
        for (int j = 0; j < plan.nsets; j++) {
            lanes_isa isa = plan.sets[j];
            const lanes_kernels *k = lanes_kernels_for(isa);
            measure_single(&rows, &scene, by_width[k->wide_width], isa, LANES_SCHEME_WIDE, 0, &plan);
            /* the same rays on the trees of the other node widths the set traverses */
            for (int nw = 4; nw <= 16; nw *= 2)
                if (nw != k->wide_width && lanes_kernels_for_width(isa, nw))
                    measure_single(&rows, &scene, by_width[nw], isa, LANES_SCHEME_WIDE, nw, &plan);
            measure_packets(&rows, &scene, &accel4, isa, LANES_PACKET_RANGED, LANES_QUEUE_MAX, plan.queue_sizes[0],
                            &plan, hist);
            measure_packets(&rows, &scene, &accel4, isa, LANES_PACKET_PARTITION, LANES_QUEUE_NONE,
                            plan.queue_sizes[0], &plan, hist);
            measure_packets(&rows, &scene, &accel4, isa, LANES_PACKET_PARTITION, LANES_QUEUE_ARRIVAL,
                            plan.queue_sizes[0], &plan, hist);
            for (int q = 0; q < plan.queue_size_count; q++) {
                measure_packets(&rows, &scene, &accel4, isa, LANES_PACKET_PARTITION, LANES_QUEUE_MAX,
                                plan.queue_sizes[q], &plan, hist);
                measure_packets(&rows, &scene, &accel4, isa, LANES_PACKET_PARTITION, LANES_QUEUE_CORNER,
                                plan.queue_sizes[q], &plan, hist);
            }
        }
#ifdef LANES_HAVE_COMPARE
        primary_rows(&rows, &scene, &accel4.bvh2, &plan);
#endif
        lanes_wbvh_free(&accel8.wide);
        lanes_wbvh_free(&accel16.wide);
        lanes_render_accel_free(&accel4);
        lanes_scene_free(&scene);
    }
    cli_finish_file("study", hist_path, hist);

    char path[1024];
    snprintf(path, sizeof path, "%s/measurements.csv", out_dir);
    write_csv(path, &rows);
    snprintf(path, sizeof path, "%s/tables.md", out_dir);
    write_tables(path, &rows, scenes, nspecs, &plan);
    FILE *report = json ? stderr : stdout;
    write_plots(out_dir, &rows, scenes, nspecs, &plan, report);
    if (json) {
        write_json(stdout, &rows, out_dir);
    } else {
        FILE *t = fopen(path, "r");
        char line[1024];
        while (t && fgets(line, sizeof line, t)) fputs(line, stdout);
        if (t) fclose(t);
        printf("\nwrote %s/measurements.csv, %s/histograms.csv, %s/tables.md and the plots "
               "(util_vs_lanes_*.png, speedup_vs_lanes_*.png, packet_sizes_*.png%s)\n",
               out_dir, out_dir, out_dir, plan.queue_size_count > 1 ? ", queue_size_*.png" : "");
    }
    free(rows.rows);
    return 0;
}

const cli_command cli_cmd_study = {
    .name = "study",
    .summary = "the width-scaling study: utilization, packet sizes, render times per ISA",
    .usage = "usage: lanes study [SCENE...] [options]\n"
             "with no scene: a short study of the embedded default scene; with --full and no\n"
             "scene: dragon, sponza-bunny, 20-bunnies and hairball at 512x512 (the thesis' set)\n"
             "  --full            thesis-sized sweep: queue sizes 256..16384, 512x512, 5 runs\n"
             "  --paths           the path tracer's study instead (Afra et al. 2016): methods,\n"
             "                    stream sizes 256..16384 and 1..256 clustered materials at every\n"
             "                    set but scalar, Embree as the intersector, and the stream's\n"
             "                    extension rays through each intersection call of lanes and\n"
             "                    Embree; 128x128, 8 spp (a tile fills a 2048-path stream;\n"
             "                    --full: sponza-bunny, 256x256,\n"
             "                    16 spp, 5 runs); into out/paths unless --out\n"
             "  --out DIR         output folder (default out/study, --paths: out/paths)\n"
             "  --size WxH        image size (default 256x256; --full: 512x512)\n"
             "  --reps N          timed runs per configuration, median reported (default 3)\n"
             "  --packet N        rays per packet (default 1024)\n"
             "  --threads N       threads per render (default 1: the thesis' single core)\n"
             "  --json            print every measurement as JSON on stdout\n"
             "  --isa NAME        study scalar and NAME only\n",
    .run = study_run,
};
