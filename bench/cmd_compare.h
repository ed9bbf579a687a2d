/* `lanes compare`: lanes against Embree on the same rays (see cmd_compare.c). */
#ifndef LANES_BENCH_CMD_COMPARE_H
#define LANES_BENCH_CMD_COMPARE_H

#include "bench/cli_common.h"

/* The entry for the CLI's command table. */
extern const cli_command cli_cmd_compare;

/* The same command for a caller without a cli_context: argv holds the words
 * after "compare". Returns the exit status (2 for bad arguments). */
int lanes_cmd_compare(int argc, char **argv);

#endif
