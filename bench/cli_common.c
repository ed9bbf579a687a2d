/* Shared pieces of the `lanes` CLI; see cli_common.h. */
#define _POSIX_C_SOURCE 200809L /* clock_gettime under -std=c11 */

#include "bench/cli_common.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

static void list_commands(FILE *out, const char *prefix, const cli_command *group)
{
    for (const cli_command *const *c = group->subcommands; c && *c; c++) {
        char name[96];
        int len = snprintf(name, sizeof name, "%s%s%s", prefix, *prefix ? " " : "", (*c)->name);
        if (len < 0 || (size_t)len >= sizeof name) continue; /* cannot happen with our tables */
        if ((*c)->subcommands)
            list_commands(out, name, *c);
        else
            fprintf(out, "  %-16s %s\n", name, (*c)->summary);
    }
}

/* Usage texts say CLI_ISA_NAMES where the kernel sets' names go, so that
 * they come from the one list of sets. */
static void print_usage_text(FILE *out, const char *text)
{
    const char *mark = CLI_ISA_NAMES;
    for (const char *at; (at = strstr(text, mark)) != NULL; text = at + strlen(mark)) {
        fwrite(text, 1, (size_t)(at - text), out);
        fputs(lanes_isa_all_names(), out);
    }
    fputs(text, out);
}

void cli_print_usage(FILE *out, const char *path, const cli_command *cmd)
{
    if (cmd->usage) print_usage_text(out, cmd->usage);
    if (cmd->subcommands) {
        /* The root's own name is not part of a command's words. */
        const char *prefix = strchr(path, ' ') ? strchr(path, ' ') + 1 : "";
        fprintf(out, "\ncommands:\n");
        list_commands(out, prefix, cmd);
    }
}

_Noreturn void cli_fail(const char *fmt, ...)
{
    va_list ap;
    fflush(stdout);
    fputs("lanes: ", stderr);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    exit(CLI_EXIT_USAGE);
}

void cli_make_dirs(const char *what, const char *dir)
{
    char path[4096];
    if (snprintf(path, sizeof path, "%s", dir) >= (int)sizeof path)
        cli_fail("%s: cannot create %s: the path is too long", what, dir);
    /* Each prefix ending at a '/', then the whole path: mkdir -p. */
    for (char *p = path + 1;; p++) {
        if (*p != '/' && *p != '\0') continue;
        char saved = *p;
        *p = '\0';
        struct stat st;
        if (mkdir(path, 0777) != 0 && errno != EEXIST)
            cli_fail("%s: cannot create %s: %s", what, path, strerror(errno));
        if (stat(path, &st) != 0 || !S_ISDIR(st.st_mode))
            cli_fail("%s: cannot create %s: %s is not a folder", what, dir, path);
        *p = saved;
        if (!saved) break;
    }
}

void cli_make_parent_dirs(const char *what, const char *path)
{
    const char *slash = strrchr(path, '/');
    if (!slash || slash == path) return;
    char dir[4096];
    if ((size_t)(slash - path) >= sizeof dir) cli_fail("%s: cannot write %s: the path is too long", what, path);
    memcpy(dir, path, (size_t)(slash - path));
    dir[slash - path] = '\0';
    cli_make_dirs(what, dir);
}

FILE *cli_create_file(const char *what, const char *path)
{
    cli_make_parent_dirs(what, path);
    FILE *f = fopen(path, "w");
    if (!f) cli_fail("%s: cannot write %s: %s", what, path, strerror(errno));
    return f;
}

void cli_finish_file(const char *what, const char *path, FILE *f)
{
    bool bad = ferror(f) != 0;
    int saved = errno;
    if (fclose(f) != 0 && !bad) bad = true, saved = errno;
    if (bad) cli_fail("%s: cannot write %s: %s", what, path, strerror(saved ? saved : EIO));
}

void cli_warn(const char *fmt, ...)
{
    va_list ap;
    fflush(stdout);
    fputs("lanes: warning: ", stderr);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
}

_Noreturn void cli_usage_error(const cli_context *ctx, const cli_command *cmd, const char *fmt, ...)
{
    va_list ap;
    fflush(stdout);
    fprintf(stderr, "%s: ", ctx->path);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputs("\n\n", stderr);
    cli_print_usage(stderr, ctx->path, cmd);
    exit(CLI_EXIT_USAGE);
}

static void path_append(cli_context *ctx, const char *word)
{
    size_t used = strlen(ctx->path);
    snprintf(ctx->path + used, sizeof ctx->path - used, " %s", word);
}

cli_args cli_args_begin(cli_context *ctx, const cli_command *cmd, int argc, char **argv)
{
    cli_args a = {ctx, cmd, argc, argv, -1};
    return a;
}

bool cli_args_next(cli_args *a)
{
    a->i++;
    if (a->i >= a->argc) return false;
    const char *w = a->argv[a->i];
    if (strcmp(w, "--help") == 0 || strcmp(w, "-h") == 0) {
        cli_print_usage(stdout, a->ctx->path, a->cmd);
        exit(0);
    }
    return true;
}

bool cli_flag(cli_args *a, const char *name) { return strcmp(a->argv[a->i], name) == 0; }

bool cli_value(cli_args *a, const char *name, const char **value)
{
    const char *w = a->argv[a->i];
    size_t n = strlen(name);
    if (strncmp(w, name, n) != 0) return false;
    if (w[n] == '=') {
        *value = w + n + 1;
        return true;
    }
    if (w[n] != '\0') return false;
    if (a->i + 1 >= a->argc) cli_usage_error(a->ctx, a->cmd, "option %s needs a value", name);
    *value = a->argv[++a->i];
    return true;
}

bool cli_global_option(cli_args *a)
{
    const char *v;
    if (cli_value(a, "--isa", &v)) {
        cli_apply_isa(a->ctx, v);
        return true;
    }
    return false;
}

_Noreturn void cli_unknown_option(const cli_args *a)
{
    const char *w = a->argv[a->i];
    if (w[0] == '-')
        cli_usage_error(a->ctx, a->cmd, "unknown option '%s'", w);
    cli_usage_error(a->ctx, a->cmd, "unexpected argument '%s'", w);
}

unsigned long cli_parse_count(const cli_args *a, const char *option, const char *text,
                              unsigned long min, unsigned long max)
{
    char *end;
    errno = 0;
    /* strtoul accepts "-1" and wraps it; digits only avoids that surprise. */
    bool digits = text[0] >= '0' && text[0] <= '9';
    unsigned long v = digits ? strtoul(text, &end, 10) : 0;
    if (!digits || *end != '\0' || errno == ERANGE || v < min || v > max)
        cli_usage_error(a->ctx, a->cmd, "%s: expected an integer from %lu to %lu, got '%s'",
                        option, min, max, text);
    return v;
}

void cli_parse_size(const cli_args *a, const char *option, const char *text, int max, int *w, int *h)
{
    char tail;
    if (sscanf(text, "%dx%d%c", w, h, &tail) != 2 || *w < 1 || *h < 1 || *w > max || *h > max)
        cli_usage_error(a->ctx, a->cmd, "%s wants WIDTHxHEIGHT, each 1..%d, not '%s'", option, max, text);
}

double cli_parse_real(const cli_args *a, const char *option, const char *text, double min, double max)
{
    char *end;
    errno = 0;
    double v = strtod(text, &end);
    if (text[0] == '\0' || *end != '\0' || errno == ERANGE || !(v >= min && v <= max))
        cli_usage_error(a->ctx, a->cmd, "%s: expected a number from %g to %g, got '%s'", option, min,
                        max, text);
    return v;
}

void cli_apply_isa(cli_context *ctx, const char *name)
{
    char why[256];
    lanes_status st = lanes_set_isa_by_name(name, why, sizeof why);
    if (st != LANES_OK) cli_fail("--isa %s: %s", name, why);
    ctx->forced_isa = lanes_isa_from_name(name);
}

const char *cli_isa_selection_reason(const cli_context *ctx, char *buf, size_t size)
{
    const char *force = getenv("LANES_ISA");
    const char *cap = getenv("LANES_MAX_ISA");
    if (ctx->forced_isa != LANES_ISA_NONE)
        snprintf(buf, size, "forced by --isa");
    else if (force && *force)
        snprintf(buf, size, "forced by LANES_ISA=%s", force);
    else if (cap && *cap)
        snprintf(buf, size, "best supported set at or below LANES_MAX_ISA=%s", cap);
    else
        snprintf(buf, size, "best supported set");
    return buf;
}

int cli_dispatch(cli_context *ctx, const cli_command *group, int argc, char **argv)
{
    int i = 0;
    /* Global options may come before the command name. */
    while (i < argc && argv[i][0] == '-') {
        cli_args a = {ctx, group, argc, argv, i - 1};
        cli_args_next(&a); /* answers --help */
        if (!cli_global_option(&a)) cli_unknown_option(&a);
        i = a.i + 1;
    }
    if (i >= argc) {
        char names[256] = "";
        size_t used = 0;
        for (const cli_command *const *c = group->subcommands; c && *c; c++) {
            int n = snprintf(names + used, sizeof names - used, "%s%s", used ? ", " : "", (*c)->name);
            if (n < 0 || (size_t)n >= sizeof names - used) break;
            used += (size_t)n;
        }
        cli_usage_error(ctx, group, "missing command (one of: %s)", names);
    }

    const char *name = argv[i];
    const cli_command *cmd = NULL;
    for (const cli_command *const *c = group->subcommands; c && *c; c++)
        if (strcmp((*c)->name, name) == 0) cmd = *c;
    if (!cmd) cli_usage_error(ctx, group, "unknown command '%s'", name);

    path_append(ctx, cmd->name);
    if (cmd->subcommands) return cli_dispatch(ctx, cmd, argc - i - 1, argv + i + 1);
    return cmd->run(ctx, cmd, argc - i - 1, argv + i + 1);
}

cli_cpu_signature cli_cpu_signature_read(void)
{
    cli_cpu_signature s = {0, 0, 0};
    uint32_t a, b, c, d;
    /* cpuid is a baseline x86-64 instruction; no intrinsics header needed. */
    __asm__("cpuid" : "=a"(a), "=b"(b), "=c"(c), "=d"(d) : "a"(0u), "c"(0u));
    if (a < 1) return s;
    __asm__("cpuid" : "=a"(a), "=b"(b), "=c"(c), "=d"(d) : "a"(1u), "c"(0u));
    unsigned base_family = (a >> 8) & 0xf, base_model = (a >> 4) & 0xf;
    s.family = base_family == 0xf ? base_family + ((a >> 20) & 0xff) : base_family;
    s.model = (base_family == 0xf || base_family == 0x6) ? base_model | (((a >> 16) & 0xf) << 4)
                                                         : base_model;
    s.stepping = a & 0xf;
    return s;
}

/* Made once, on the first call (from the main thread): the CPU does not
 * change during a run. */
const char *cli_cpu_description(void)
{
    static char text[160];
    if (!text[0]) {
        const char *brand = lanes_cpu()->brand;
        cli_cpu_signature sig = cli_cpu_signature_read();
        snprintf(text, sizeof text, "%s (family 0x%x, model 0x%x)", brand[0] ? brand : "unknown CPU",
                 sig.family, sig.model);
    }
    return text;
}

#define CLI_STR_(x) #x
#define CLI_VERSION_(a, b, c) CLI_STR_(a) "." CLI_STR_(b) "." CLI_STR_(c)
const char *cli_compiler(void)
{
#if defined(__clang__)
    return "clang " CLI_VERSION_(__clang_major__, __clang_minor__, __clang_patchlevel__);
#elif defined(__GNUC__)
    return "gcc " CLI_VERSION_(__GNUC__, __GNUC_MINOR__, __GNUC_PATCHLEVEL__);
#else
    return "unknown compiler";
#endif
}

/* Length of the valid UTF-8 sequence at s, or 0 when it is not valid. */
static size_t utf8_length(const unsigned char *s)
{
    unsigned char c = s[0];
    size_t n;
    uint32_t cp;
    if (c < 0x80) return 1;
    if (c >= 0xc2 && c <= 0xdf) n = 2, cp = c & 0x1f;
    else if (c >= 0xe0 && c <= 0xef) n = 3, cp = c & 0x0f;
    else if (c >= 0xf0 && c <= 0xf4) n = 4, cp = c & 0x07;
    else return 0;
    for (size_t k = 1; k < n; k++) {
        if ((s[k] & 0xc0) != 0x80) return 0;
        cp = (cp << 6) | (s[k] & 0x3f);
    }
    /* overlong forms, surrogates and values past U+10FFFF are not UTF-8 */
    if ((n == 3 && cp < 0x800) || (n == 4 && cp < 0x10000) || cp > 0x10ffff ||
        (cp >= 0xd800 && cp <= 0xdfff))
        return 0;
    return n;
}

void cli_json_number(FILE *out, double x)
{
    if (isnan(x) || isinf(x))
        fputs("null", out);
    else
        fprintf(out, "%.6g", x);
}

void cli_json_string(FILE *out, const char *s)
{
    const unsigned char *p = (const unsigned char *)(s ? s : "");
    fputc('"', out);
    while (*p) {
        unsigned char c = *p;
        if (c == '"' || c == '\\') {
            fputc('\\', out), fputc(c, out), p++;
        } else if (c == '\n') {
            fputs("\\n", out), p++;
        } else if (c == '\t') {
            fputs("\\t", out), p++;
        } else if (c == '\r') {
            fputs("\\r", out), p++;
        } else if (c < 0x20 || c == 0x7f) {
            fprintf(out, "\\u%04x", c), p++;
        } else {
            size_t n = utf8_length(p);
            if (n == 0) {
                fputs("\\ufffd", out), p++;
            } else {
                fwrite(p, 1, n, out), p += n;
            }
        }
    }
    fputc('"', out);
}

void cli_csv_field(FILE *out, const char *s)
{
    if (!s) s = "";
    if (strpbrk(s, ",\"\r\n") == NULL) {
        fputs(s, out);
        return;
    }
    fputc('"', out);
    for (; *s; s++) {
        if (*s == '"') fputc('"', out);
        fputc(*s, out);
    }
    fputc('"', out);
}

uint64_t cli_now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
}

uint64_t cli_thread_cpu_ns(void)
{
    struct timespec ts;
    if (clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts) != 0) return 0;
    return (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

double cli_median(double *v, size_t n)
{
    if (n == 0) return 0.0;
    qsort(v, n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

void cli_progress_step(cli_progress *p, const char *what)
{
    p->done++;
    if (isatty(2)) {
        fprintf(stderr, "\r[%3d/%3d] %-70.70s", p->done, p->total, what);
        if (p->done == p->total) fprintf(stderr, "\n");
    } else {
        fprintf(stderr, "[%d/%d] %s\n", p->done, p->total, what);
    }
    fflush(stderr);
}

cli_progress_bar cli_progress_bar_make(void) { return (cli_progress_bar){isatty(2) != 0, -1}; }

void cli_show_progress(void *bar, double fraction)
{
    cli_progress_bar *p = bar;
    int pct = (int)(fraction * 100.0);
    if (!p->tty || pct == p->last) return;
    p->last = pct;
    int filled = pct * 40 / 100;
    fprintf(stderr, "\r[%.*s%*s] %3d%%", filled, "########################################", 40 - filled, "", pct);
    if (pct == 100) fprintf(stderr, "\n");
    fflush(stderr);
}
