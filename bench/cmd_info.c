/* `lanes info`: what this CPU offers, what this build contains, and which
 * instruction set runs. The JSON form is for scripts and for the studies'
 * records, so each figure carries the machine it came from. */
#include <stdio.h>

#include "bench/cli_commands.h"
#include "bench/cli_common.h"
#include "simd/isa.h"

static const char *const xcr0_names[] = {
    [0] = "x87",       [1] = "sse",       [2] = "avx",       [3] = "bndregs",
    [4] = "bndcsr",    [5] = "opmask",    [6] = "zmm_hi256", [7] = "hi16_zmm",
    [9] = "pkru",      [17] = "tilecfg",  [18] = "tiledata",
};

typedef struct {
    const lanes_cpu_features *cpu;
    cli_cpu_signature sig;
    uint32_t disabled; /* detected, but switched off by LANES_DISABLE_CPU_FEATURES */
    lanes_isa selected;
    char reason[160];
} info;

static void print_text(const info *in)
{
    char buf[512];
    const lanes_cpu_features *cpu = in->cpu;

    printf("cpu:          %s\n", cpu->brand[0] ? cpu->brand : "(no brand string)");
    printf("vendor:       %s (family 0x%x, model 0x%x, stepping %u)\n",
           cpu->vendor[0] ? cpu->vendor : "unknown", in->sig.family, in->sig.model,
           in->sig.stepping);
    lanes_cpu_feature_list(cpu->bits, buf, sizeof buf);
    printf("features:     %s\n", buf[0] ? buf : "(none)");
    printf("compiler:     %s\n", cli_compiler());
    uint32_t not_enabled = cpu->cpuid_bits & ~cpu->raw_bits;
    if (not_enabled) {
        lanes_cpu_feature_list(not_enabled, buf, sizeof buf);
        printf("os-disabled:  %s (in cpuid, but the OS has not enabled their state)\n", buf);
    }
    if (in->disabled) {
        lanes_cpu_feature_list(in->disabled, buf, sizeof buf);
        printf("disabled:     %s (by LANES_DISABLE_CPU_FEATURES)\n", buf);
    }
    printf("xcr0:         ");
    if (cpu->bits & LANES_CPU_OSXSAVE) {
        printf("0x%016llx (", (unsigned long long)cpu->xcr0);
        const char *sep = "";
        for (unsigned b = 0; b < 64; b++) {
            if (!(cpu->xcr0 & (1ull << b))) continue;
            const char *name = b < sizeof xcr0_names / sizeof xcr0_names[0] ? xcr0_names[b] : NULL;
            if (name)
                printf("%s%s", sep, name);
            else
                printf("%sbit%u", sep, b);
            sep = " ";
        }
        printf(")\n");
    } else {
        printf("unavailable (the OS has not set OSXSAVE)\n");
    }

    printf("compiled:     ");
    const char *sep = "";
    for (int i = 0; i < LANES_ISA_COUNT; i++)
        if (lanes_isa_compiled((lanes_isa)i)) {
            printf("%s%s", sep, lanes_isa_name((lanes_isa)i));
            sep = " ";
        }
    printf("\nsupported:    ");
    sep = "";
    for (int i = 0; i < LANES_ISA_COUNT; i++) {
        if (!lanes_isa_supported((lanes_isa)i)) continue;
        printf("%s%s (%d lane%s)", sep, lanes_isa_name((lanes_isa)i), lanes_isa_lanes((lanes_isa)i),
               lanes_isa_lanes((lanes_isa)i) == 1 ? "" : "s");
        sep = ", ";
    }
    printf("\n");
    for (int i = 0; i < LANES_ISA_COUNT; i++) {
        lanes_isa isa = (lanes_isa)i;
        if (lanes_isa_supported(isa)) continue;
        if (!lanes_isa_compiled(isa)) {
            printf("not built:    %s (left out of LANES_ISAS or not supported by the compiler)\n",
                   lanes_isa_name(isa));
            continue;
        }
        lanes_cpu_explain_missing(cpu, lanes_isa_required_features(isa), buf, sizeof buf);
        printf("cannot run:   %s (%s)\n", lanes_isa_name(isa), buf);
    }
    printf("selected:     %s (%d lane%s; %s)\n", lanes_isa_name(in->selected),
           lanes_isa_lanes(in->selected), lanes_isa_lanes(in->selected) == 1 ? "" : "s",
           in->reason);
}

static void json_feature_array(uint32_t bits)
{
    const char *sep = "";
    printf("[");
    for (int i = 0; i < LANES_CPU_FEATURE_COUNT; i++) {
        if (!(bits & (1u << i))) continue;
        printf("%s", sep);
        cli_json_string(stdout, lanes_cpu_feature_name(1u << i));
        sep = ", ";
    }
    printf("]");
}

static void json_isa_array(bool (*pick)(lanes_isa))
{
    const char *sep = "";
    printf("[");
    for (int i = 0; i < LANES_ISA_COUNT; i++) {
        if (!pick((lanes_isa)i)) continue;
        printf("%s", sep);
        cli_json_string(stdout, lanes_isa_name((lanes_isa)i));
        sep = ", ";
    }
    printf("]");
}

static void print_json(const info *in)
{
    const lanes_cpu_features *cpu = in->cpu;

    printf("{\n  \"cpu\": ");
    cli_json_string(stdout, cpu->brand);
    printf(",\n  \"vendor\": ");
    cli_json_string(stdout, cpu->vendor);
    printf(",\n  \"family\": %u,\n  \"model\": %u,\n  \"stepping\": %u,\n", in->sig.family,
           in->sig.model, in->sig.stepping);
    printf("  \"compiler\": ");
    cli_json_string(stdout, cli_compiler());
    printf(",\n");
    printf("  \"features\": ");
    json_feature_array(cpu->bits);
    printf(",\n  \"features_detected\": ");
    json_feature_array(cpu->raw_bits);
    printf(",\n  \"features_cpuid\": ");
    json_feature_array(cpu->cpuid_bits);
    printf(",\n  \"disabled_features\": ");
    json_feature_array(in->disabled);
    /* A string: a 64-bit mask does not survive JSON readers that use doubles. */
    printf(",\n  \"xcr0\": \"0x%016llx\",\n", (unsigned long long)cpu->xcr0);
    printf("  \"compiled\": ");
    json_isa_array(lanes_isa_compiled);
    printf(",\n  \"supported\": ");
    json_isa_array(lanes_isa_supported);
    printf(",\n  \"isas\": [\n");
    for (int i = 0; i < LANES_ISA_COUNT; i++) {
        lanes_isa isa = (lanes_isa)i;
        printf("    {\"name\": ");
        cli_json_string(stdout, lanes_isa_name(isa));
        printf(", \"lanes\": %d, \"compiled\": %s, \"cpu_can_run\": %s, \"supported\": %s, "
               "\"missing_features\": ",
               lanes_isa_lanes(isa), lanes_isa_compiled(isa) ? "true" : "false",
               lanes_isa_cpu_can_run(isa) ? "true" : "false",
               lanes_isa_supported(isa) ? "true" : "false");
        uint32_t missing = lanes_isa_required_features(isa) & ~cpu->bits;
        json_feature_array(missing);
        printf("}%s\n", i + 1 < LANES_ISA_COUNT ? "," : "");
    }
    printf("  ],\n  \"selected\": ");
    cli_json_string(stdout, lanes_isa_name(in->selected));
    printf(",\n  \"lanes\": %d,\n  \"selected_by\": ", lanes_isa_lanes(in->selected));
    cli_json_string(stdout, in->reason);
    printf("\n}\n");
}

static int info_run(cli_context *ctx, const cli_command *self, int argc, char **argv)
{
    bool json = false;
    cli_args a = cli_args_begin(ctx, self, argc, argv);
    while (cli_args_next(&a)) {
        if (cli_flag(&a, "--json"))
            json = true;
        else if (!cli_global_option(&a))
            cli_unknown_option(&a);
    }

    info in;
    in.cpu = lanes_cpu();
    in.sig = cli_cpu_signature_read();
    in.disabled = in.cpu->raw_bits & ~in.cpu->bits;
    in.selected = lanes_isa_current();
    cli_isa_selection_reason(ctx, in.reason, sizeof in.reason);
    if (json)
        print_json(&in);
    else
        print_text(&in);
    return fflush(stdout) == 0 ? 0 : 1;
}

const cli_command cli_cmd_info = {
    .name = "info",
    .summary = "CPU, features, compiled and runnable instruction sets, the selected one",
    .usage = "usage: lanes info [--json] [--isa NAME]\n"
             "\n"
             "  --json        one JSON object on stdout (cpu, vendor, features, compiled,\n"
             "                supported, selected, lanes, ...)\n"
             "  --isa NAME    select NAME first (shows what 'selected' becomes)\n",
    .run = info_run,
};
