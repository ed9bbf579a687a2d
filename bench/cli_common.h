/* Shared pieces of the `lanes` command-line tool: the command table type,
 * option parsing, error reporting and output helpers.
 *
 * Compiled for the x86-64 baseline like all of bench/: the CLI reaches the
 * kernels only through the lanes_kernels tables, never through intrinsics. */
#ifndef LANES_BENCH_CLI_COMMON_H
#define LANES_BENCH_CLI_COMMON_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "simd/isa.h"

/* Exit status of every usage or input error (the design's "exit status 2"). */
#define CLI_EXIT_USAGE 2
/* In a usage text: replaced by the kernel sets' names when printed. */
#define CLI_ISA_NAMES "<kernel sets>"

#if defined(__GNUC__)
#define CLI_PRINTF(fmt, args) __attribute__((format(printf, fmt, args)))
#else
#define CLI_PRINTF(fmt, args)
#endif

/* State shared by the whole invocation. */
typedef struct cli_context {
    lanes_isa forced_isa; /* set by --isa (before or after the command), else LANES_ISA_NONE */
    char path[96];        /* "lanes bench kernels": the command being run, for messages */
} cli_context;

typedef struct cli_command cli_command;

/* One entry of a command table. A leaf has `run`; a group ("bench") has a
 * NULL-terminated list of subcommands instead. Adding a command means one
 * file defining a cli_command and one line in a table in lanes_cli.c. */
struct cli_command {
    const char *name;
    const char *summary; /* one line, for the command list */
    const char *usage;   /* synopsis and options, for --help and usage errors */
    int (*run)(cli_context *ctx, const cli_command *self, int argc, char **argv);
    const cli_command *const *subcommands;
};

/* Runs argv (the words after the group's own name) against a group: global
 * options, then the command name, then recursion or the leaf's run(). */
int cli_dispatch(cli_context *ctx, const cli_command *group, int argc, char **argv);
/* Prints the usage of a command; for a group, also the commands under it. */
void cli_print_usage(FILE *out, const char *path, const cli_command *cmd);

/* "lanes: <message>" on stderr, exit status 2. */
_Noreturn void cli_fail(const char *fmt, ...) CLI_PRINTF(1, 2);
/* "<path>: <message>" and the command's usage on stderr, exit status 2. */
_Noreturn void cli_usage_error(const cli_context *ctx, const cli_command *cmd, const char *fmt, ...)
    CLI_PRINTF(3, 4);
/* Output files. Each creates the folders the path needs, and a failure
 * ends the run (status 2) with the path and the OS's reason, prefixed by
 * `what` ("study", "--csv"). */
void cli_make_dirs(const char *what, const char *dir);
/* The folders above a file's path. */
void cli_make_parent_dirs(const char *what, const char *path);
FILE *cli_create_file(const char *what, const char *path);
/* Closes a file made by cli_create_file; a write error ends the run. */
void cli_finish_file(const char *what, const char *path, FILE *f);

/* "lanes: warning: <message>" on stderr; the run goes on. */
void cli_warn(const char *fmt, ...) CLI_PRINTF(1, 2);

/* Option parsing for a leaf command:
 *
 *     cli_args a = cli_args_begin(ctx, self, argc, argv);
 *     while (cli_args_next(&a)) {
 *         if (cli_flag(&a, "--json")) json = true;
 *         else if (cli_value(&a, "--csv", &path)) ...;
 *         else if (!cli_global_option(&a)) cli_unknown_option(&a);
 *     }
 *
 * cli_args_next() answers --help/-h itself (usage on stdout, exit 0). */
typedef struct cli_args {
    cli_context *ctx;
    const cli_command *cmd;
    int argc;
    char **argv;
    int i; /* index of the current word */
} cli_args;

cli_args cli_args_begin(cli_context *ctx, const cli_command *cmd, int argc, char **argv);
bool cli_args_next(cli_args *a);
bool cli_flag(cli_args *a, const char *name);
/* Matches "--name VALUE" and "--name=VALUE"; a missing value is a usage error. */
bool cli_value(cli_args *a, const char *name, const char **value);
/* Options valid with every command (--isa NAME). */
bool cli_global_option(cli_args *a);
_Noreturn void cli_unknown_option(const cli_args *a);
/* A decimal integer in [min, max]; anything else is a usage error naming the option. */
unsigned long cli_parse_count(const cli_args *a, const char *option, const char *text,
                              unsigned long min, unsigned long max);
/* WIDTHxHEIGHT, each 1..max, into *w and *h; anything else is a usage error
 * naming the option. */
void cli_parse_size(const cli_args *a, const char *option, const char *text, int max, int *w, int *h);
/* A finite real number in [min, max]; anything else is a usage error naming the option. */
double cli_parse_real(const cli_args *a, const char *option, const char *text, double min, double max);

/* --isa NAME: forces the set through lanes_set_isa_by_name(); an unknown
 * name or a set this CPU cannot run ends the program with status 2. */
void cli_apply_isa(cli_context *ctx, const char *name);
/* Why the active set is the active set: "--isa", "LANES_ISA", ... */
const char *cli_isa_selection_reason(const cli_context *ctx, char *buf, size_t size);

/* CPU signature from cpuid leaf 1 (family with the extended family added,
 * as AMD and Intel document it). Zeros when cpuid leaf 1 is absent. */
typedef struct cli_cpu_signature {
    unsigned family, model, stepping;
} cli_cpu_signature;
cli_cpu_signature cli_cpu_signature_read(void);
/* "AMD EPYC (family 0x19, model 0x11)": a brand string alone may not tell
 * one generation from the next (a Zen 4 virtual machine has reported
 * just "AMD EPYC"), and every figure needs its CPU. */
const char *cli_cpu_description(void);
/* The compiler that built this program, and with it the kernels (one
 * CMake configure compiles both): "clang 14.0.6", "gcc 12.2.0". The same
 * kernels ran 7-10% apart between those two at avx2 and avx512, and 1.6x
 * at avx512emu (README), so a figure needs it too. */
const char *cli_compiler(void);

/* JSON string literal with quotes; invalid UTF-8 bytes become U+FFFD so the
 * document stays valid whatever the CPU's brand string holds. */
void cli_json_string(FILE *out, const char *s);
/* JSON number with 6 significant digits; null for NaN and infinities,
 * which JSON cannot hold. */
void cli_json_number(FILE *out, double x);
/* CSV field, quoted only when it needs to be (RFC 4180). */
void cli_csv_field(FILE *out, const char *s);

/* A progress bar on stderr, drawn only on a terminal and only when the
 * shown percentage changes: the renderers' progress callback. */
typedef struct {
    bool tty;
    int last;
} cli_progress_bar;
cli_progress_bar cli_progress_bar_make(void);
void cli_show_progress(void *bar, double fraction);

/* Monotonic time in nanoseconds. */
uint64_t cli_now_ns(void);
/* CPU time the calling thread has used, in nanoseconds: compared with
 * cli_now_ns() it shows whether the thread had its CPU to itself. */
uint64_t cli_thread_cpu_ns(void);
/* Median of n doubles (sorts them in place); 0 for n == 0. */
double cli_median(double *v, size_t n);

/* Progress of a long command on stderr: one line per step, redrawn in place
 * on a terminal, appended otherwise (CI logs). */
typedef struct cli_progress {
    int done, total;
} cli_progress;
void cli_progress_step(cli_progress *p, const char *what);

#endif
