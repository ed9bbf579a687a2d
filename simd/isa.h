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

/* Ordered by preference for the automatic choice; avx512emu sits below avx512
 * only for listing, it is never chosen automatically. */
typedef enum lanes_isa {
    LANES_ISA_SCALAR = 0,
    LANES_ISA_SSE4,
    LANES_ISA_AVX,
    LANES_ISA_AVX2,
    LANES_ISA_AVX512EMU,
    LANES_ISA_AVX512,
    LANES_ISA_COUNT,
    LANES_ISA_NONE = -1
} lanes_isa;

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

/* Name ("scalar", "sse4", "avx", "avx2", "avx512emu", "avx512") and lane count. */
const char *lanes_isa_name(lanes_isa isa);
int lanes_isa_lanes(lanes_isa isa);
/* LANES_ISA_NONE for an unknown name. */
lanes_isa lanes_isa_from_name(const char *name);
/* The CPU features a set needs, as LANES_CPU_* bits. */
uint32_t lanes_isa_required_features(lanes_isa isa);
/* Was this set compiled into the library (LANES_ISAS at configure time)? */
bool lanes_isa_compiled(lanes_isa isa);
/* Can this CPU (after the disable switch) run the set? */
bool lanes_isa_cpu_can_run(lanes_isa isa);
/* Compiled and runnable. */
bool lanes_isa_supported(lanes_isa isa);

/* The best native set this CPU runs, capped by LANES_MAX_ISA (or by
 * lanes_set_max_isa), among those compiled in. Never avx512emu. */
lanes_isa lanes_isa_best(void);

typedef enum lanes_status {
    LANES_OK = 0,
    LANES_ERR_UNKNOWN_ISA,    /* a name that is no set */
    LANES_ERR_NOT_COMPILED,   /* a set left out of this build */
    LANES_ERR_CPU_LACKS,      /* the CPU (or OS) cannot run the set */
    LANES_ERR_BAD_INPUT       /* e.g. an unknown name in LANES_DISABLE_CPU_FEATURES */
} lanes_status;

/* The active set. On first use it is chosen from LANES_ISA (forces a set),
 * else LANES_MAX_ISA (caps the automatic choice), else the best set.
 * lanes_isa_init() reports a bad environment value through its status and
 * message (an unknown name in LANES_DISABLE_CPU_FEATURES as LANES_ERR_BAD_INPUT,
 * which no --isa or lanes_set_isa() can override); lanes_isa_current() falls back to the best set after such an error
 * has been reported, so library callers that ignore the status still never
 * run an instruction the CPU lacks. */
lanes_status lanes_isa_init(char *message, size_t message_size);
lanes_isa lanes_isa_current(void);
/* Force a set (LANES_ISA_NONE returns to the automatic choice). On error the
 * active set is unchanged and message says why, naming the missing feature. */
lanes_status lanes_set_isa(lanes_isa isa, char *message, size_t message_size);
lanes_status lanes_set_isa_by_name(const char *name, char *message, size_t message_size);
lanes_status lanes_set_max_isa(lanes_isa cap, char *message, size_t message_size);

/* Comma-separated list of every set name, for messages. */
const char *lanes_isa_all_names(void);

#endif
