/* `lanes`: the command-line tool. This file holds only the command tables,
 * the global options and the usage; each command lives in its own file
 * (cmd_*.c) and is reached through the tables below.
 *
 *     lanes [--isa NAME] <command> [options]      (--isa may also follow the command)
 *
 * Instruction-set choice: --isa > LANES_ISA > LANES_MAX_ISA cap > best. */
#include <stdbool.h>
#include <stdio.h>
#include <string.h>

#include "bench/cli_commands.h"
#include "bench/cli_common.h"

/* Studies under `lanes bench`; later ones (traversal, ...) go here. */
static const cli_command *const bench_commands[] = {
    &cli_cmd_bench_kernels,
    NULL,
};

static const cli_command cli_cmd_bench = {
    .name = "bench",
    .summary = "performance studies",
    .usage = "usage: lanes bench <study> [options]\n"
             "run 'lanes bench <study> --help' for a study's options\n",
    .subcommands = bench_commands,
};

static int help_run(cli_context *ctx, const cli_command *self, int argc, char **argv);

static const cli_command cli_cmd_help = {
    .name = "help",
    .summary = "describe a command: lanes help bench kernels",
    .usage = "usage: lanes help [command...]\n",
    .run = help_run,
};

static const cli_command *const commands[] = {
    &cli_cmd_info,
    &cli_cmd_render,
    &cli_cmd_paths,
#ifdef LANES_HAVE_COMPARE
    &cli_cmd_compare,
#endif
    &cli_cmd_study,
    &cli_cmd_accuracy,
    &cli_cmd_bench,
    &cli_cmd_help,
    NULL,
};

static const cli_command root = {
    .name = "lanes",
    .summary = "",
    .usage =
        "usage: lanes [--isa NAME] <command> [options]\n"
        "       lanes help [command]\n"
        "\n"
        "global options (before or after the command):\n"
        "  --isa NAME       run instruction set NAME: " CLI_ISA_NAMES "\n"
        "                   (an unknown name or a set this CPU cannot run is an error)\n"
        "  -h, --help       this text; 'lanes <command> --help' for a command's options\n"
        "\n"
        "environment:\n"
        "  LANES_ISA=NAME          force a set (--isa takes precedence)\n"
        "  LANES_MAX_ISA=NAME      cap the automatic choice\n"
        "  LANES_DISABLE_CPU_FEATURES=a,b  pretend these CPU features are absent (testing)\n"
        "\n"
        "exit status: 0 success, 2 bad usage or input\n",
    .subcommands = commands,
};

/* `lanes help [words...]`: the usage of the named command or group. */
static int help_run(cli_context *ctx, const cli_command *self, int argc, char **argv)
{
    const cli_command *cmd = &root;
    (void)self;
    snprintf(ctx->path, sizeof ctx->path, "lanes");
    for (int i = 0; i < argc; i++) {
        const cli_command *next = NULL;
        for (const cli_command *const *c = cmd->subcommands; c && *c; c++)
            if (strcmp((*c)->name, argv[i]) == 0) next = *c;
        if (!next) cli_usage_error(ctx, cmd, "no command '%s' to describe", argv[i]);
        size_t used = strlen(ctx->path);
        snprintf(ctx->path + used, sizeof ctx->path - used, " %s", next->name);
        cmd = next;
    }
    cli_print_usage(stdout, ctx->path, cmd);
    return 0;
}

int main(int argc, char **argv)
{
    char message[256];
    cli_context ctx = {.forced_isa = LANES_ISA_NONE, .path = "lanes"};

    /* A bad LANES_ISA or LANES_MAX_ISA is the user's error: say so rather
     * than run with a set they did not ask for. --isa takes precedence over
     * the environment, so with --isa the environment's error does not stop
     * the run (the set --isa names is checked when it is applied); a bad
     * LANES_DISABLE_CPU_FEATURES does, since --isa does not replace it. */
    bool isa_flag = false;
    for (int i = 1; i < argc; i++)
        if (strcmp(argv[i], "--isa") == 0 || strncmp(argv[i], "--isa=", 6) == 0) isa_flag = true;
    lanes_status st = lanes_isa_init(message, sizeof message);
    if (st != LANES_OK && (!isa_flag || st == LANES_ERR_BAD_INPUT)) cli_fail("%s", message);

    return cli_dispatch(&ctx, &root, argc - 1, argv + 1);
}
