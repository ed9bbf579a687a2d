/* `lanes accuracy`: what each accuracy mode costs and buys at every kernel
 * set. For each closed mesh, each translation, each mode and each set: rays
 * leaking out of the closed mesh, false hits on rays that just miss, the
 * error of t in ulps, self-intersections of secondary rays and the
 * throughput, as one table, a CSV, a JSON document and a gnuplot picture of
 * throughput against leaks. The measuring itself is accuracy_measure.c. */
#define _DEFAULT_SOURCE /* mkdir */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "bench/accuracy_measure.h"
#include "bench/cli_commands.h"
#include "bench/cli_common.h"
#include "build/scenes_builtin.h"
#include "trace/render.h"

#define MAX_MESHES 8
#define MAX_TRANSLATIONS 16

typedef struct {
    char mesh[64];
    double translation;
    lanes_accuracy mode;
    lanes_isa isa;
    bool no_interior; /* the rounded mesh kept no interior: leak figures are n/a */
    acc_counts c;
    double mrays;
} acc_row;

typedef struct {
    acc_row *rows;
    size_t n, cap;
} row_list;

typedef struct {
    const char *meshes[MAX_MESHES];
    bool mesh_is_file[MAX_MESHES];
    int nmeshes;
    double translations[MAX_TRANSLATIONS];
    int ntranslations;
    bool modes[LANES_ACCURACY_COUNT];
    bool isas[LANES_ISA_COUNT];
    double size;
    uint64_t rays, aimed_rays, miss_rays, self_from;
    size_t time_rays;
    int reps, threads;
    uint64_t seed;
} acc_plan;

static acc_row *add_row(row_list *l)
{
    if (l->n == l->cap) {
        size_t cap = l->cap ? 2 * l->cap : 64;
        acc_row *p = realloc(l->rows, cap * sizeof *p);
        if (!p) cli_fail("accuracy: out of memory");
        l->rows = p, l->cap = cap;
    }
    acc_row *r = &l->rows[l->n++];
    memset(r, 0, sizeof *r);
    r->mrays = NAN;
    return r;
}

static double per_1e7(uint64_t events, uint64_t rays, bool na)
{
    return na || rays == 0 ? NAN : (double)events / (double)rays * 1e7;
}

static double row_leaks(const acc_row *r) { return per_1e7(r->c.leaks, r->c.rays, r->no_interior); }
static double row_aimed(const acc_row *r) { return per_1e7(r->c.aimed_leaks, r->c.aimed_rays, r->no_interior); }
static double row_false(const acc_row *r) { return per_1e7(r->c.false_hits, r->c.miss_rays, false); }
static double row_self(const acc_row *r) { return per_1e7(r->c.self_hits, r->c.self_rays, r->no_interior); }

/* ---- progress -------------------------------------------------------- */

static cli_progress progress_bar;

static void progress(const char *what) { cli_progress_step(&progress_bar, what); }

/* ---- output ---------------------------------------------------------- */

static void put_number(FILE *f, double x, const char *fmt, const char *missing)
{
    if (isnan(x))
        fputs(missing, f);
    else
        fprintf(f, fmt, x);
}

/* Names reach awk filters and CSV fields: keep them plain. */
static void plain_name(char *dst, size_t size, const char *src)
{
    const char *base = strrchr(src, '/');
    snprintf(dst, size, "%s", base ? base + 1 : src);
    for (char *p = dst; *p; p++)
        if (*p == ',' || *p == '"' || *p == '\'' || *p == '\\' || (unsigned char)*p < 32) *p = '_';
}

static const char *csv_header =
    "mesh,translation,mode,isa,lanes,rays,leaks,leaks_per_1e7,aimed_rays,aimed_leaks,aimed_leaks_per_1e7,"
    "miss_rays,false_hits,false_hits_per_1e7,"
    "self_rays,self_hits,self_hits_per_1e7,t_samples,t_ulp_p50,t_ulp_p99,mrays\n";

static void write_csv(const char *path, const row_list *rows)
{
    FILE *f = cli_create_file("accuracy", path);
    fputs(csv_header, f);
    for (size_t i = 0; i < rows->n; i++) {
        const acc_row *r = &rows->rows[i];
        bool na = r->no_interior;
        fprintf(f, "%s,%g,%s,%s,%d,%llu,", r->mesh, r->translation, lanes_accuracy_name(r->mode),
                lanes_isa_name(r->isa), lanes_isa_lanes(r->isa), (unsigned long long)r->c.rays);
        if (!na) fprintf(f, "%llu", (unsigned long long)r->c.leaks);
        fputc(',', f);
        put_number(f, row_leaks(r), "%.6g", "");
        fprintf(f, ",%llu,", (unsigned long long)r->c.aimed_rays);
        if (!na) fprintf(f, "%llu", (unsigned long long)r->c.aimed_leaks);
        fputc(',', f);
        put_number(f, row_aimed(r), "%.6g", "");
        fprintf(f, ",%llu,%llu,", (unsigned long long)r->c.miss_rays, (unsigned long long)r->c.false_hits);
        put_number(f, row_false(r), "%.6g", "");
        fprintf(f, ",%llu,", (unsigned long long)r->c.self_rays);
        if (!na) fprintf(f, "%llu", (unsigned long long)r->c.self_hits);
        fputc(',', f);
        put_number(f, row_self(r), "%.6g", "");
        fprintf(f, ",%llu,", (unsigned long long)r->c.t_samples);
        put_number(f, acc_ulp_percentile(&r->c, 0.5), "%.0f", "");
        fputc(',', f);
        put_number(f, acc_ulp_percentile(&r->c, 0.99), "%.0f", "");
        fputc(',', f);
        put_number(f, r->mrays, "%.4g", "");
        fputc('\n', f);
    }
    cli_finish_file("accuracy", path, f);
}

static void write_histograms(const char *path, const row_list *rows)
{
    FILE *f = cli_create_file("accuracy", path);
    fprintf(f, "mesh,translation,mode,isa,ulp_from,ulp_to,count\n");
    for (size_t i = 0; i < rows->n; i++) {
        const acc_row *r = &rows->rows[i];
        for (int b = 0; b < ACC_ULP_BINS; b++) {
            if (!r->c.t_hist[b]) continue;
            unsigned long long lo = acc_ulp_bin_low(b);
            unsigned long long hi = b + 1 < ACC_ULP_BINS ? acc_ulp_bin_low(b + 1) - 1 : ~0ull;
            fprintf(f, "%s,%g,%s,%s,%llu,%llu,%llu\n", r->mesh, r->translation, lanes_accuracy_name(r->mode),
                    lanes_isa_name(r->isa), lo, hi, (unsigned long long)r->c.t_hist[b]);
        }
    }
    cli_finish_file("accuracy", path, f);
}

static void write_json(FILE *f, const row_list *rows, const acc_plan *plan, const char *dir)
{
    fprintf(f, "{\"cpu\": ");
    cli_json_string(f, lanes_cpu()->brand);
    fprintf(f, ", \"size\": %g, \"rays\": %llu, \"folder\": ", plan->size, (unsigned long long)plan->rays);
    cli_json_string(f, dir);
    fprintf(f, ", \"rows\": [");
    for (size_t i = 0; i < rows->n; i++) {
        const acc_row *r = &rows->rows[i];
        fprintf(f, "%s\n  {\"mesh\": ", i ? "," : "");
        cli_json_string(f, r->mesh);
        fprintf(f, ", \"translation\": %g, \"mode\": \"%s\", \"isa\": \"%s\", \"leaks_per_1e7\": ", r->translation,
                lanes_accuracy_name(r->mode), lanes_isa_name(r->isa));
        cli_json_number(f, row_leaks(r));
        fprintf(f, ", \"aimed_leaks_per_1e7\": ");
        cli_json_number(f, row_aimed(r));
        fprintf(f, ", \"false_hits_per_1e7\": ");
        cli_json_number(f, row_false(r));
        fprintf(f, ", \"self_hits_per_1e7\": ");
        cli_json_number(f, row_self(r));
        fprintf(f, ", \"t_ulp_p50\": ");
        cli_json_number(f, acc_ulp_percentile(&r->c, 0.5));
        fprintf(f, ", \"t_ulp_p99\": ");
        cli_json_number(f, acc_ulp_percentile(&r->c, 0.99));
        fprintf(f, ", \"mrays\": ");
        cli_json_number(f, r->mrays);
        fprintf(f, ", \"rays\": %llu, \"leaks\": ", (unsigned long long)r->c.rays);
        cli_json_number(f, r->no_interior ? NAN : (double)r->c.leaks);
        fprintf(f, ", \"aimed_rays\": %llu, \"aimed_leaks\": ", (unsigned long long)r->c.aimed_rays);
        cli_json_number(f, r->no_interior ? NAN : (double)r->c.aimed_leaks);
        fprintf(f, ", \"miss_rays\": %llu, \"false_hits\": %llu, \"self_rays\": %llu, \"self_hits\": ",
                (unsigned long long)r->c.miss_rays, (unsigned long long)r->c.false_hits,
                (unsigned long long)r->c.self_rays);
        cli_json_number(f, r->no_interior ? NAN : (double)r->c.self_hits);
        fprintf(f, "}");
    }
    fprintf(f, "\n]}\n");
}

static const acc_row *find(const row_list *rows, const char *mesh, double translation, lanes_accuracy mode,
                           lanes_isa isa)
{
    for (size_t i = 0; i < rows->n; i++) {
        const acc_row *r = &rows->rows[i];
        if (strcmp(r->mesh, mesh) == 0 && r->translation == translation && r->mode == mode && r->isa == isa) return r;
    }
    return NULL;
}

/* Throughput of mode a over mode b at one set and mesh: the geometric mean
 * over the translations where both were timed (one translation's ratio
 * is as noisy as two timings; the mean of several is steadier). */
static double ratio(const row_list *rows, const acc_plan *plan, const char *mesh, lanes_isa isa, lanes_accuracy a,
                    lanes_accuracy b)
{
    double log_sum = 0.0;
    int n = 0;
    for (int t = 0; t < plan->ntranslations; t++) {
        const acc_row *ra = find(rows, mesh, plan->translations[t], a, isa);
        const acc_row *rb = find(rows, mesh, plan->translations[t], b, isa);
        if (!ra || !rb || !(ra->mrays > 0.0) || !(rb->mrays > 0.0)) continue;
        log_sum += log(ra->mrays / rb->mrays);
        n++;
    }
    return n ? exp(log_sum / n) : NAN;
}

static void write_tables(FILE *f, const row_list *rows, const acc_plan *plan, char meshes[][64],
                         char notes[][320])
{
    fprintf(f, "# lanes accuracy\n\nCPU: %s; built by %s. Each mesh scaled to a bounding-box diagonal of %g and "
               "centred on the origin, then every coordinate translated by T and rounded to float.\n",
            cli_cpu_description(), cli_compiler(), plan->size);
    for (int m = 0; m < plan->nmeshes; m++)
        if (notes[m][0]) fprintf(f, "Note: %s.\n", notes[m]);
    fprintf(f,
            "\nEvery row of a mesh and translation traces the same rays. leaks/1e7: of %llu rays per row from %d "
            "interior points (at least %g from the surface) in random directions, those that report no hit. "
            "aimed/1e7: the same for %llu rays per row from those points aimed at mesh vertices and edge midpoints "
            "(where a test that is not watertight loses rays). false/1e7: of rays that miss the whole mesh by 1/16 "
            "to 8 ulps of the coordinates there beside a silhouette edge (exact test), those that report a hit. "
            "self/1e7: of the reflected and "
            "transmitted rays spawned at the hits of the first %llu leak rays (origin from lanes_offset_origin), "
            "those whose closest hit is the triangle they leave. t ulp: integer ulp distance of t from the exact "
            "distance to the hit triangle's plane, rounded to float (p50, p99; values from 64 up are the lower end "
            "of a power-of-two bin). Mrays/s: trace_wide, one thread, median of %d runs of %zu rays.\n\n",
            (unsigned long long)plan->rays, ACC_POINTS, ACC_CLEARANCE * plan->size,
            (unsigned long long)plan->aimed_rays, (unsigned long long)plan->self_from,
            plan->reps, plan->time_rays);
    fprintf(f, "| mesh | translation | mode | isa | leaks/1e7 | aimed/1e7 | false hits/1e7 | self hits/1e7 | "
               "t ulp p50 | t ulp p99 | Mrays/s |\n|---|---:|---|---|---:|---:|---:|---:|---:|---:|---:|\n");
    for (size_t i = 0; i < rows->n; i++) {
        const acc_row *r = &rows->rows[i];
        fprintf(f, "| %s | %g | %s | %s | ", r->mesh, r->translation, lanes_accuracy_name(r->mode),
                lanes_isa_name(r->isa));
        put_number(f, row_leaks(r), "%.0f", "n/a");
        fputs(" | ", f);
        put_number(f, row_aimed(r), "%.0f", "n/a");
        fputs(" | ", f);
        put_number(f, row_false(r), "%.0f", "n/a");
        fputs(" | ", f);
        put_number(f, row_self(r), "%.0f", "n/a");
        fputs(" | ", f);
        put_number(f, acc_ulp_percentile(&r->c, 0.5), "%.0f", "n/a");
        fputs(" | ", f);
        put_number(f, acc_ulp_percentile(&r->c, 0.99), "%.0f", "n/a");
        fputs(" | ", f);
        put_number(f, r->mrays, "%.2f", "n/a");
        fputs(" |\n", f);
    }
    bool have_fd = plan->modes[LANES_ACCURACY_FAST] && plan->modes[LANES_ACCURACY_DEFAULT];
    bool have_dr = plan->modes[LANES_ACCURACY_DEFAULT] && plan->modes[LANES_ACCURACY_ROBUST];
    if (!have_fd && !have_dr) return;
    fprintf(f, "\nThroughput ratios (geometric mean over the translations):\n\n| mesh | isa | robust/default | "
               "default/fast |\n|---|---|---:|---:|\n");
    for (int m = 0; m < plan->nmeshes; m++)
        for (int i = 0; i < LANES_ISA_COUNT; i++) {
            if (!plan->isas[i]) continue;
            fprintf(f, "| %s | %s | ", meshes[m], lanes_isa_name((lanes_isa)i));
            put_number(f, ratio(rows, plan, meshes[m], (lanes_isa)i, LANES_ACCURACY_ROBUST, LANES_ACCURACY_DEFAULT),
                       "%.3f", "n/a");
            fputs(" | ", f);
            put_number(f, ratio(rows, plan, meshes[m], (lanes_isa)i, LANES_ACCURACY_DEFAULT, LANES_ACCURACY_FAST),
                       "%.3f", "n/a");
            fputs(" |\n", f);
        }
}

/* One point of the picture per mesh, mode and set: leaks over all the
 * translations (where the mesh kept an interior) and the geometric mean of
 * the throughputs. most[] receives the largest rate of each kind, for the
 * axes. */
static void write_trade(const char *path, const row_list *rows, const acc_plan *plan, char meshes[][64],
                        double most[2])
{
    FILE *f = cli_create_file("accuracy", path);
    fprintf(f, "mesh,mode,isa,leaks_per_1e7,aimed_leaks_per_1e7,mrays\n");
    most[0] = most[1] = 0.0;
    for (int m = 0; m < plan->nmeshes; m++)
        for (int mode = 0; mode < LANES_ACCURACY_COUNT; mode++)
            for (int i = 0; i < LANES_ISA_COUNT; i++) {
                uint64_t rays = 0, leaks = 0, aimed_rays = 0, aimed_leaks = 0;
                double log_sum = 0.0;
                int timed = 0;
                for (size_t k = 0; k < rows->n; k++) {
                    const acc_row *r = &rows->rows[k];
                    if (strcmp(r->mesh, meshes[m]) || r->mode != (lanes_accuracy)mode || r->isa != (lanes_isa)i ||
                        r->no_interior)
                        continue;
                    rays += r->c.rays, leaks += r->c.leaks;
                    aimed_rays += r->c.aimed_rays, aimed_leaks += r->c.aimed_leaks;
                    if (r->mrays > 0.0) log_sum += log(r->mrays), timed++;
                }
                if (!rays || !timed) continue;
                double rate = (double)leaks / (double)rays * 1e7;
                double aimed = aimed_rays ? (double)aimed_leaks / (double)aimed_rays * 1e7 : 0.0;
                most[0] = fmax(most[0], rate);
                most[1] = fmax(most[1], aimed);
                fprintf(f, "%s,%s,%s,%.6g,%.6g,%.4g\n", meshes[m], lanes_accuracy_name((lanes_accuracy)mode),
                        lanes_isa_name((lanes_isa)i), rate, aimed, exp(log_sum / timed));
            }
    cli_finish_file("accuracy", path, f);
}

/* Mrays/s against leaks: a column per mesh, a row per kind of leak ray
 * (random directions; aimed at vertices and edges), one point series per
 * mode, each point a set (labelled). Leak rates of 0 must show on a log
 * axis, so x is leaks per 1e7 plus 1: no leaks sit at 1. */
static void write_plot(const char *dir, const row_list *rows, char meshes[][64], const acc_plan *plan, FILE *report)
{
    char path[2048], cmd[4200];
    snprintf(path, sizeof path, "%s/trade.csv", dir);
    double most[2], xmax[2];
    write_trade(path, rows, plan, meshes, most);
    if (system("command -v gnuplot >/dev/null 2>&1") != 0) {
        fprintf(report, "plot: gnuplot not found (install gnuplot-nox); the CSV files are written\n");
        return;
    }
    int nmeshes = plan->nmeshes > 0 ? plan->nmeshes : 1;
    for (int kind = 0; kind < 2; kind++)
        for (xmax[kind] = 100.0; xmax[kind] < 4.0 * (most[kind] + 1.0);) xmax[kind] *= 10.0;
    char brand[64];
    plain_name(brand, sizeof brand, lanes_cpu()->brand);
    char script[16384];
    int used = snprintf(script, sizeof script,
                        "set datafile separator ','\nset terminal pngcairo size %d,1100\n"
                        "set output 'accuracy_trade.png'\n"
                        "set multiplot layout 2,%d title \"Throughput against leaks: %s, size %g\\n%llu random "
                        "and %llu aimed rays x %d translation(s); one point per set; Mrays/s: geometric mean over "
                        "the translations\"\n"
                        "set logscale x\nset format x '10^{%%L}'\nset grid\nset key below horizontal\n"
                        "set ylabel 'Mrays/s (trace\\_wide, 1 thread)'\n"
                        "f(m,mode)=sprintf(\"< awk -F, '$1==\\\"%%s\\\" && $2==\\\"%%s\\\"' trade.csv\", m, mode)\n",
                        nmeshes < 2 ? 1000 : 520 * nmeshes, nmeshes, brand, plan->size,
                        (unsigned long long)plan->rays, (unsigned long long)plan->aimed_rays, plan->ntranslations);
    static const int point_type[LANES_ACCURACY_COUNT] = {7, 5, 9};
    static const struct {
        int column;
        const char *label, *title;
    } kinds[2] = {{4, "leaks per 10^7 rays in random directions + 1 (no leaks at 1)", "random directions"},
                  {5, "leaks per 10^7 rays aimed at vertices and edges + 1", "aimed at vertices and edges"}};
    for (int kind = 0; kind < 2; kind++)
        for (int m = 0; m < plan->nmeshes && used > 0 && (size_t)used < sizeof script; m++) {
            used += snprintf(script + used, sizeof script - (size_t)used,
                             "set title '%s: %s'\nset xlabel '%s'\nset xrange [0.5:%g]\nplot ", meshes[m],
                             kinds[kind].title, kinds[kind].label, xmax[kind]);
            bool first = true;
            for (int mode = 0; mode < LANES_ACCURACY_COUNT && used > 0 && (size_t)used < sizeof script; mode++) {
                if (!plan->modes[mode]) continue;
                const char *name = lanes_accuracy_name((lanes_accuracy)mode);
                int x = kinds[kind].column;
                used += snprintf(script + used, sizeof script - (size_t)used,
                                 "%sf('%s','%s') using ($%d+1):6 with points pt %d ps 1.4 lc %d title '%s', "
                                 "f('%s','%s') using ($%d+1):6:3 with labels offset char 1.2,%d left font ',8' "
                                 "tc lt %d notitle",
                                 first ? "" : ", ", meshes[m], name, x, point_type[mode], mode + 1, name, meshes[m],
                                 name, x, mode - 1, mode + 1);
                first = false;
            }
            if (used > 0 && (size_t)used < sizeof script)
                used += snprintf(script + used, sizeof script - (size_t)used, "\n");
        }
    if (used < 0 || (size_t)used >= sizeof script - 32) {
        fprintf(report, "plot: too many meshes for one picture\n");
        return;
    }
    snprintf(script + used, sizeof script - (size_t)used, "unset multiplot\n");
    snprintf(path, sizeof path, "%s/accuracy_trade.gp", dir);
    FILE *f = fopen(path, "w");
    if (!f) {
        fprintf(report, "plot: cannot write %s: %s\n", path, strerror(errno));
        return;
    }
    fputs(script, f);
    fclose(f);
    snprintf(cmd, sizeof cmd, "cd '%s' && gnuplot accuracy_trade.gp 2>gnuplot.log", dir);
    if (system(cmd) != 0) fprintf(report, "plot: gnuplot failed (see %s/gnuplot.log)\n", dir);
}

/* ---- arguments ------------------------------------------------------- */

/* Splits a comma-separated list in place. */
static int split(char *s, char **out, int max)
{
    int n = 0;
    for (char *p = s;;) {
        char *comma = strchr(p, ',');
        if (comma) *comma = '\0';
        if (n == max) return -1;
        out[n++] = p;
        if (!comma) break;
        p = comma + 1;
    }
    return n;
}

static char *copy_arg(const char *s)
{
    size_t n = strlen(s) + 1;
    char *c = malloc(n);
    if (!c) cli_fail("accuracy: out of memory");
    memcpy(c, s, n);
    return c;
}

static void parse_translations(cli_context *ctx, const cli_command *self, const char *value, acc_plan *plan)
{
    char *list = copy_arg(value), *items[MAX_TRANSLATIONS];
    int n = split(list, items, MAX_TRANSLATIONS);
    if (n < 0) cli_usage_error(ctx, self, "--translations: at most %d values", MAX_TRANSLATIONS);
    for (int i = 0; i < n; i++) {
        char *end;
        errno = 0;
        double t = strtod(items[i], &end);
        if (items[i][0] == '\0' || *end != '\0' || errno == ERANGE || !isfinite(t) || fabs(t) > 1e30)
            cli_usage_error(ctx, self, "--translations: '%s' is not a number from -1e30 to 1e30", items[i]);
        plan->translations[i] = t;
    }
    plan->ntranslations = n;
    free(list);
}

static void parse_modes(cli_context *ctx, const cli_command *self, const char *value, acc_plan *plan)
{
    char *list = copy_arg(value), *items[8];
    int n = split(list, items, 8);
    if (n < 0) cli_usage_error(ctx, self, "--mode: too many modes");
    memset(plan->modes, 0, sizeof plan->modes);
    for (int i = 0; i < n; i++) {
        int m = lanes_accuracy_from_name(items[i]);
        if (m < 0) cli_usage_error(ctx, self, "--mode: unknown mode '%s' (fast, default, robust)", items[i]);
        plan->modes[m] = true;
    }
    free(list);
}

static void parse_meshes(cli_context *ctx, const cli_command *self, const char *value, acc_plan *plan,
                         char **storage)
{
    char *list = copy_arg(value), *items[MAX_MESHES];
    int n = split(list, items, MAX_MESHES);
    if (n < 0) cli_usage_error(ctx, self, "--meshes: at most %d meshes", MAX_MESHES);
    for (int i = 0; i < n; i++) {
        if (items[i][0] == '\0') cli_usage_error(ctx, self, "--meshes: empty name in '%s'", value);
        plan->meshes[i] = items[i];
        plan->mesh_is_file[i] = false;
    }
    plan->nmeshes = n;
    *storage = list;
}

static bool is_builtin_object(const char *name)
{
    static const char *const objects[] = {"sphere", "box", "cylinder", "bunny", "dragon", "armadillo", "elephant"};
    for (size_t i = 0; i < sizeof objects / sizeof objects[0]; i++)
        if (strcmp(name, objects[i]) == 0) return true;
    return false;
}

/* ---- the command ----------------------------------------------------- */

static int accuracy_run(cli_context *ctx, const cli_command *self, int argc, char **argv)
{
    const char *out_dir = "out/accuracy", *value, *scene = NULL;
    char *mesh_storage = NULL;
    bool json = false, aimed_given = false, miss_given = false, self_given = false, time_given = false;
    acc_plan plan = {.size = ACC_DEFAULT_SIZE, .rays = 1000000, .reps = 3, .threads = 0, .seed = 1};
    plan.nmeshes = 3;
    plan.meshes[0] = "sphere", plan.meshes[1] = "bunny", plan.meshes[2] = "dragon";
    plan.ntranslations = 4;
    plan.translations[0] = 0, plan.translations[1] = 1e3, plan.translations[2] = 1e5, plan.translations[3] = 1e7;
    for (int m = 0; m < LANES_ACCURACY_COUNT; m++) plan.modes[m] = true;

    cli_args a = cli_args_begin(ctx, self, argc, argv);
    while (cli_args_next(&a)) {
        if (cli_flag(&a, "--json")) {
            json = true;
        } else if (cli_value(&a, "--out", &out_dir)) {
        } else if (cli_value(&a, "--rays", &value)) {
            plan.rays = cli_parse_count(&a, "--rays", value, 1, 4000000000ul);
        } else if (cli_value(&a, "--aimed-rays", &value)) {
            plan.aimed_rays = cli_parse_count(&a, "--aimed-rays", value, 0, 4000000000ul);
            aimed_given = true;
        } else if (cli_value(&a, "--miss-rays", &value)) {
            plan.miss_rays = cli_parse_count(&a, "--miss-rays", value, 0, 100000000ul);
            miss_given = true;
        } else if (cli_value(&a, "--self-rays", &value)) {
            plan.self_from = cli_parse_count(&a, "--self-rays", value, 0, 4000000000ul);
            self_given = true;
        } else if (cli_value(&a, "--time-rays", &value)) {
            plan.time_rays = cli_parse_count(&a, "--time-rays", value, 0, 100000000ul);
            time_given = true;
        } else if (cli_value(&a, "--reps", &value)) {
            plan.reps = (int)cli_parse_count(&a, "--reps", value, 1, 16);
        } else if (cli_value(&a, "--threads", &value)) {
            plan.threads = (int)cli_parse_count(&a, "--threads", value, 1, 64);
        } else if (cli_value(&a, "--seed", &value)) {
            plan.seed = cli_parse_count(&a, "--seed", value, 0, 4000000000ul);
        } else if (cli_value(&a, "--size", &value)) {
            char *end;
            errno = 0;
            plan.size = strtod(value, &end);
            if (*end != '\0' || value[0] == '\0' || errno == ERANGE || !(plan.size >= 1e-6 && plan.size <= 1e9))
                cli_usage_error(ctx, self, "--size: expected a number from 1e-6 to 1e9, got '%s'", value);
        } else if (cli_value(&a, "--translations", &value)) {
            parse_translations(ctx, self, value, &plan);
        } else if (cli_value(&a, "--mode", &value)) {
            parse_modes(ctx, self, value, &plan);
        } else if (cli_value(&a, "--meshes", &value)) {
            free(mesh_storage);
            parse_meshes(ctx, self, value, &plan, &mesh_storage);
        } else if (cli_global_option(&a)) {
        } else if (a.argv[a.i][0] != '-' && !scene) {
            scene = a.argv[a.i];
        } else {
            cli_unknown_option(&a);
        }
    }
    if (scene) {
        /* a built-in object by name, unless a file of that name is meant
         * (./name); anything else is a mesh file */
        struct stat st;
        bool file = !is_builtin_object(scene) || stat(scene, &st) == 0;
        if (file && strlen(scene) > 5 && strcmp(scene + strlen(scene) - 5, ".json") == 0)
            cli_fail("accuracy: %s: a scene file; lanes accuracy measures one closed mesh (a mesh file or one of "
                     "sphere, bunny, dragon, ...)",
                     scene);
        for (size_t i = 0; file && stat(scene, &st) != 0 && i < lanes_builtin_scene_count(); i++)
            if (strcmp(scene, lanes_builtin_scene_info(i)->name) == 0)
                cli_fail("accuracy: %s: a built-in scene; lanes accuracy measures one closed mesh (a mesh file or "
                         "one of sphere, bunny, dragon, ...)",
                         scene);
        plan.nmeshes = 1;
        plan.meshes[0] = scene;
        plan.mesh_is_file[0] = file;
    }
    if (!aimed_given) plan.aimed_rays = plan.rays / 10;
    if (!miss_given) plan.miss_rays = plan.rays / 10;
    if (!self_given) plan.self_from = plan.rays / 10;
    if (plan.self_from > plan.rays) plan.self_from = plan.rays;
    if (!time_given) plan.time_rays = plan.rays < 65536 ? (size_t)plan.rays : 65536;
    for (int i = 0; i < LANES_ISA_COUNT; i++)
        plan.isas[i] = lanes_isa_supported((lanes_isa)i) &&
                       (ctx->forced_isa == LANES_ISA_NONE || (lanes_isa)i == ctx->forced_isa);
    unsigned widths = 0;
    int nisa = 0, nmodes = 0;
    for (int i = 0; i < LANES_ISA_COUNT; i++)
        if (plan.isas[i]) widths |= acc_width_bit(lanes_kernels_for((lanes_isa)i)->wide_width), nisa++;
    for (int m = 0; m < LANES_ACCURACY_COUNT; m++) nmodes += plan.modes[m];

    /* meshes first: a bad file or an open mesh is reported before any work */
    lanes_mesh meshes[MAX_MESHES];
    char names[MAX_MESHES][64], notes[MAX_MESHES][320];
    for (int m = 0; m < plan.nmeshes; m++) {
        lanes_error err;
        if (acc_mesh_load(plan.meshes[m], plan.mesh_is_file[m], &meshes[m], notes[m], sizeof notes[m],
                          &err) != LANES_OK)
            cli_fail("accuracy: %s", err.message);
        plain_name(names[m], sizeof names[m], plan.meshes[m]);
    }
    cli_make_dirs("accuracy", out_dir);

    FILE *report = json ? stderr : stdout;
    char sets[128] = "";
    for (int i = 0; i < LANES_ISA_COUNT; i++)
        if (plan.isas[i])
            snprintf(sets + strlen(sets), sizeof sets - strlen(sets), "%s%s", sets[0] ? " " : "",
                     lanes_isa_name((lanes_isa)i));
    fprintf(report, "CPU: %s; built by %s; sets: %s; size %g; translations", cli_cpu_description(), cli_compiler(),
            sets, plan.size);
    for (int t = 0; t < plan.ntranslations; t++) fprintf(report, "%s%g", t ? ", " : " ", plan.translations[t]);
    fprintf(report, "\n");
    fflush(report);

    progress_bar.total = plan.nmeshes * plan.ntranslations * nisa * nmodes;
    row_list rows = {0};
    double t_start = lanes_render_clock();
    for (int m = 0; m < plan.nmeshes; m++) {
        for (int t = 0; t < plan.ntranslations; t++) {
            acc_world w;
            lanes_error err;
            if (acc_world_build(&w, names[m], &meshes[m], plan.size, plan.translations[t], widths,
                                plan.threads, plan.seed, &err) != LANES_OK ||
                acc_world_misses(&w, plan.miss_rays, plan.threads, &err) != LANES_OK)
                cli_fail("accuracy: %s", err.message);
            for (int i = 0; i < LANES_ISA_COUNT; i++) {
                if (!plan.isas[i]) continue;
                const lanes_kernels *k = lanes_kernels_for((lanes_isa)i);
                for (int mode = 0; mode < LANES_ACCURACY_COUNT; mode++) {
                    if (!plan.modes[mode]) continue;
                    acc_row *r = add_row(&rows);
                    snprintf(r->mesh, sizeof r->mesh, "%.63s", names[m]);
                    r->translation = plan.translations[t];
                    r->mode = (lanes_accuracy)mode;
                    r->isa = (lanes_isa)i;
                    r->no_interior = w.point_count == 0;
                    acc_job job = {.k = k,
                                   .mode = (lanes_accuracy)mode,
                                   .via = ACC_VIA_WIDE,
                                   .first = 0,
                                   .count = r->no_interior ? 0 : plan.rays,
                                   .t_error = true,
                                   .self_from = r->no_interior ? 0 : plan.self_from,
                                   .false_hits = true,
                                   .threads = plan.threads};
                    if (acc_measure(&w, &job, &r->c, &err) != LANES_OK) cli_fail("accuracy: %s", err.message);
                    acc_job aimed = {.k = k,
                                     .mode = (lanes_accuracy)mode,
                                     .via = ACC_VIA_WIDE,
                                     .count = r->no_interior ? 0 : plan.aimed_rays,
                                     .aimed = true,
                                     .threads = plan.threads};
                    if (acc_measure(&w, &aimed, &r->c, &err) != LANES_OK)
                        cli_fail("accuracy: %s", err.message);
                    if (!r->no_interior)
                        r->mrays = acc_time_wide(&w, k, (lanes_accuracy)mode, plan.time_rays, plan.reps);
                    char what[160];
                    snprintf(what, sizeof what, "%.63s at %g: %s, %s", names[m], plan.translations[t],
                             lanes_accuracy_name((lanes_accuracy)mode), lanes_isa_name((lanes_isa)i));
                    progress(what);
                }
            }
            if (w.point_count == 0)
                fprintf(stderr, "accuracy: %s at translation %g: no interior point among %zu candidates "
                                "(the rounding collapsed the mesh): leak figures n/a\n",
                        names[m], plan.translations[t], w.point_candidates);
            else if (w.miss_count < plan.miss_rays)
                fprintf(stderr, "accuracy: %s at translation %g: %zu near-miss rays of %llu asked for\n", names[m],
                        plan.translations[t], w.miss_count, (unsigned long long)plan.miss_rays);
            acc_world_free(&w);
        }
    }
    double seconds = lanes_render_clock() - t_start;

    char path[2048];
    snprintf(path, sizeof path, "%s/accuracy.csv", out_dir);
    write_csv(path, &rows);
    snprintf(path, sizeof path, "%s/t_ulp_histograms.csv", out_dir);
    write_histograms(path, &rows);
    snprintf(path, sizeof path, "%s/accuracy.json", out_dir);
    FILE *jf = cli_create_file("accuracy", path);
    write_json(jf, &rows, &plan, out_dir);
    cli_finish_file("accuracy", path, jf);
    snprintf(path, sizeof path, "%s/tables.md", out_dir);
    FILE *md = cli_create_file("accuracy", path);
    write_tables(md, &rows, &plan, names, notes);
    cli_finish_file("accuracy", path, md);
    write_plot(out_dir, &rows, names, &plan, report);
    if (json) {
        write_json(stdout, &rows, &plan, out_dir);
    } else {
        write_tables(stdout, &rows, &plan, names, notes);
        printf("\n%zu rows in %.1f s; wrote %s/tables.md, accuracy.csv, accuracy.json, t_ulp_histograms.csv, "
               "trade.csv and accuracy_trade.png\n",
               rows.n, seconds, out_dir);
    }
    for (int m = 0; m < plan.nmeshes; m++) lanes_mesh_free(&meshes[m]);
    free(mesh_storage);
    free(rows.rows);
    return 0;
}

const cli_command cli_cmd_accuracy = {
    .name = "accuracy",
    .summary = "leaks, false hits, t error, self-hits and speed of the fast, default and robust modes",
    .usage =
        "usage: lanes accuracy [SCENE] [options]\n"
        "For each closed mesh, translation, accuracy mode and instruction set:\n"
        "  leaks       rays shot from points inside the closed mesh (random directions) that report\n"
        "              no hit, per 10^7 rays; every one of them must hit\n"
        "  aimed       the same for rays from those points aimed at mesh vertices and edge\n"
        "              midpoints, where a test that is not watertight loses rays\n"
        "  false hits  rays that miss the mesh by 1/16 to 8 ulps of the coordinates beside a\n"
        "              silhouette edge (checked by an exact test) but report a hit, per 10^7\n"
        "  t ulp       error of t against the exact distance, in float ulps (median, 99th percentile)\n"
        "  self hits   reflected and transmitted rays spawned at hits that hit their own triangle,\n"
        "              per 10^7 secondary rays\n"
        "  Mrays/s     closest-hit throughput of the leak rays, trace_wide, one thread, median\n"
        "The mesh is scaled to a bounding-box diagonal of --size, centred on the origin, every\n"
        "coordinate translated by T and rounded to float. Prints one table (and throughput ratios\n"
        "robust/default and default/fast) and writes tables.md, accuracy.csv, accuracy.json,\n"
        "t_ulp_histograms.csv, trade.csv and accuracy_trade.png (Mrays/s against leaks per mode\n"
        "and set, gnuplot) to --out.\n"
        "The default run (3 meshes, 4 translations, 3 modes, every set: 216 rows of 10^6 rays)\n"
        "takes 1 to 1.5 minutes on two cores.\n"
        "\n"
        "  SCENE               a closed mesh file (OBJ, PLY, OFF, STL, ...) or a built-in object\n"
        "                      (sphere, bunny, dragon, box, cylinder, armadillo, elephant); replaces\n"
        "                      --meshes. A mesh that is not closed is refused (exit status 2)\n"
        "  --meshes LIST       built-in objects, comma-separated (default sphere,bunny,dragon; the\n"
        "                      sphere is an icosphere of 5120 triangles; the dragon's two small holes\n"
        "                      are filled)\n"
        "  --translations LIST T values, comma-separated (default 0,1e3,1e5,1e7)\n"
        "  --size S            bounding-box diagonal (default 100)\n"
        "  --mode LIST         modes, comma-separated: fast, default, robust (default all three)\n"
        "  --rays N            leak rays per mesh, translation, mode and set (default 1000000)\n"
        "  --aimed-rays N      aimed leak rays per mesh, translation, mode and set (default rays/10)\n"
        "  --miss-rays N       near-miss rays per mesh and translation (default rays/10)\n"
        "  --self-rays N       leak rays whose hits spawn two secondary rays each (default rays/10)\n"
        "  --time-rays N       rays per timed run (default min(rays, 65536))\n"
        "  --reps N            timed runs, median reported (default 3)\n"
        "  --threads N         threads for the BVH build and the (untimed) counting (default: all\n"
        "                      cores); the timing always runs on one thread\n"
        "  --seed N            seed of the points and rays (default 1)\n"
        "  --out DIR           output folder (default out/accuracy)\n"
        "  --json              print {\"rows\": [{mesh, translation, mode, isa, leaks_per_1e7,\n"
        "                      aimed_leaks_per_1e7,\n"
        "                      false_hits_per_1e7, self_hits_per_1e7, t_ulp_p50, t_ulp_p99, mrays, ...}]}\n"
        "                      on stdout (the table then goes to tables.md only); n/a is null\n"
        "  --isa NAME          measure that set only\n",
    .run = accuracy_run,
};
