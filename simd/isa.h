/* Instruction sets ("kernel sets") lanes compiles its kernels for, CPU feature
 * detection, and the choice of the set that runs.
 *
 * Compiled for the x86-64 baseline: nothing here may include an intrinsics
 * header, because this code runs before we know what the CPU can execute. */
#ifndef LANES_SIMD_ISA_H
#define LANES_SIMD_ISA_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "lanes/lanes.h"

/* lanes_isa and the choice of the active set (lanes_isa_name ... lanes_set_max_isa)
 * are public: lanes/lanes.h. What follows is internal: CPU features. */

/* CPU features lanes cares about, as bits of lanes_cpu_features.bits. */
enum {
    LANES_CPU_SSE2 = 1u << 0,
    LANES_CPU_SSE3 = 1u << 1,
    LANES_CPU_SSSE3 = 1u << 2,
    LANES_CPU_SSE41 = 1u << 3,
    LANES_CPU_SSE42 = 1u << 4,
    LANES_CPU_POPCNT = 1u << 5,
    LANES_CPU_OSXSAVE = 1u << 6, /* the OS saves extended state: xgetbv is usable */
    LANES_CPU_AVX = 1u << 7,     /* CPU has AVX and the OS saves YMM state */
    LANES_CPU_F16C = 1u << 8,
    LANES_CPU_FMA = 1u << 9,
    LANES_CPU_AVX2 = 1u << 10,
    LANES_CPU_BMI1 = 1u << 11,
    LANES_CPU_BMI2 = 1u << 12,
    LANES_CPU_LZCNT = 1u << 13,
    LANES_CPU_AVX512F = 1u << 14, /* CPU has AVX-512F and the OS saves ZMM and opmask state */
    LANES_CPU_AVX512CD = 1u << 15,
    LANES_CPU_AVX512DQ = 1u << 16,
    LANES_CPU_AVX512BW = 1u << 17,
    LANES_CPU_AVX512VL = 1u << 18,
    LANES_CPU_FEATURE_COUNT = 19
};

/* Three views of the same features, from the CPU outwards: what cpuid says the
 * processor has, what of that the OS has enabled (OSXSAVE and the XCR0
 * register state), and what the test-only disable switch leaves. A set that
 * cannot run is explained at the first view that lacks a feature it needs. */
typedef struct lanes_cpu_features {
    uint32_t bits;          /* LANES_CPU_* after the test-only disable switch */
    uint32_t raw_bits;      /* usable: the CPU has it and the OS enabled its state */
    uint32_t cpuid_bits;    /* the processor reports it, whatever the OS enabled */
    uint64_t xcr0;          /* 0 when xgetbv is not usable */
    char vendor[13];
    char brand[49];
    /* The first name in LANES_DISABLE_CPU_FEATURES that is no feature, or "". */
    char unknown_disabled[32];
} lanes_cpu_features;

/* Detected once, then cached. The environment variable
 * LANES_DISABLE_CPU_FEATURES (a comma-separated list of feature names as
 * lanes_cpu_feature_name() spells them, e.g. "avx512f,avx2") makes the
 * detector believe those features are absent. It exists for tests: it lets
 * every selection path run on one machine. */
const lanes_cpu_features *lanes_cpu(void);
const char *lanes_cpu_feature_name(uint32_t feature_bit);
/* Writes the detected feature names, space separated, into buf. */
void lanes_cpu_feature_list(uint32_t bits, char *buf, size_t size);
/* Every feature name, comma separated, for messages. */
const char *lanes_cpu_all_feature_names(void);
/* Why features `needs` cannot all be used on `cpu`, in the order a user needs
 * it: features the processor lacks, else register state the OS has not
 * enabled, else features switched off by LANES_DISABLE_CPU_FEATURES. Writes
 * the reason (without a trailing period) and returns false when nothing is
 * missing. Pure: tests call it with CPUs this machine is not. */
bool lanes_cpu_explain_missing(const lanes_cpu_features *cpu, uint32_t needs, char *why,
                               size_t size);

/* Makes text the calling thread's lanes_last_error_message(): every failing
 * public call, here and in trace/lanes_api.c, reports through it. */
void lanes_record_error(const char *text);

/* The CPU features a set needs, as LANES_CPU_* bits. */
uint32_t lanes_isa_required_features(lanes_isa isa);

#endif
