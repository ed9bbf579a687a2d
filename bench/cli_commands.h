/* The commands of the `lanes` tool. Each lives in its own cmd_*.c file and
 * is listed in a table in lanes_cli.c. */
#ifndef LANES_BENCH_CLI_COMMANDS_H
#define LANES_BENCH_CLI_COMMANDS_H

#include "bench/cli_common.h"

extern const cli_command cli_cmd_info;          /* cmd_info.c */
extern const cli_command cli_cmd_bench_kernels; /* cmd_bench_kernels.c */
extern const cli_command cli_cmd_render;        /* cmd_render.c */
extern const cli_command cli_cmd_paths;         /* cmd_paths.c */
extern const cli_command cli_cmd_study;         /* cmd_study.c */
extern const cli_command cli_cmd_accuracy;      /* cmd_accuracy.c */
#ifdef LANES_HAVE_COMPARE
extern const cli_command cli_cmd_compare;       /* cmd_compare.c */
#endif

#endif
