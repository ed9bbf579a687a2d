/* Which kernel set runs: the names, what each needs of the CPU, and the
 * choice (forced by LANES_ISA or the API, capped by LANES_MAX_ISA, otherwise
 * the best the CPU runs). A set the CPU cannot run is refused with a message
 * naming the missing feature, never attempted. */
#include "simd/isa.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const isa_names[LANES_ISA_COUNT] = {
    "scalar", "sse4", "avx", "avx2", "avx512emu", "avx512",
};
static const int isa_lanes[LANES_ISA_COUNT] = {1, 4, 8, 8, 16, 16};

#define NEEDS_SSE4 (LANES_CPU_SSE2 | LANES_CPU_SSE41 | LANES_CPU_POPCNT)
#define NEEDS_AVX (NEEDS_SSE4 | LANES_CPU_OSXSAVE | LANES_CPU_AVX)
#define NEEDS_AVX2 (NEEDS_AVX | LANES_CPU_AVX2 | LANES_CPU_FMA)
#define NEEDS_AVX512                                                                       \
    (NEEDS_AVX2 | LANES_CPU_AVX512F | LANES_CPU_AVX512DQ | LANES_CPU_AVX512BW | LANES_CPU_AVX512VL)
static const uint32_t isa_needs[LANES_ISA_COUNT] = {
    LANES_CPU_SSE2, NEEDS_SSE4, NEEDS_AVX, NEEDS_AVX2, NEEDS_AVX2, NEEDS_AVX512,
};

/* Set by CMake for every set that configured and built (LANES_ISAS). */
static const bool isa_compiled[LANES_ISA_COUNT] = {
#ifdef LANES_HAVE_KSET_SCALAR
    [LANES_ISA_SCALAR] = true,
#endif
#ifdef LANES_HAVE_KSET_SSE4
    [LANES_ISA_SSE4] = true,
#endif
#ifdef LANES_HAVE_KSET_AVX
    [LANES_ISA_AVX] = true,
#endif
#ifdef LANES_HAVE_KSET_AVX2
    [LANES_ISA_AVX2] = true,
#endif
#ifdef LANES_HAVE_KSET_AVX512EMU
    [LANES_ISA_AVX512EMU] = true,
#endif
#ifdef LANES_HAVE_KSET_AVX512
    [LANES_ISA_AVX512] = true,
#endif
};

static bool valid(lanes_isa isa) { return isa >= 0 && isa < LANES_ISA_COUNT; }

const char *lanes_isa_name(lanes_isa isa) { return valid(isa) ? isa_names[isa] : "none"; }
int lanes_isa_lanes(lanes_isa isa) { return valid(isa) ? isa_lanes[isa] : 0; }
uint32_t lanes_isa_required_features(lanes_isa isa) { return valid(isa) ? isa_needs[isa] : 0; }
bool lanes_isa_compiled(lanes_isa isa) { return valid(isa) && isa_compiled[isa]; }

bool lanes_isa_cpu_can_run(lanes_isa isa)
{
    return valid(isa) && (lanes_cpu()->bits & isa_needs[isa]) == isa_needs[isa];
}

bool lanes_isa_supported(lanes_isa isa) { return lanes_isa_compiled(isa) && lanes_isa_cpu_can_run(isa); }

lanes_isa lanes_isa_from_name(const char *name)
{
    for (int i = 0; name && i < LANES_ISA_COUNT; i++)
        if (strcmp(name, isa_names[i]) == 0) return (lanes_isa)i;
    return LANES_ISA_NONE;
}

const char *lanes_isa_all_names(void) { return "scalar, sse4, avx, avx2, avx512emu, avx512"; }

/* The active set and the cap, as atomics: read on every kernel-table lookup. */
static _Atomic int current_isa = LANES_ISA_NONE;
static _Atomic int max_isa = LANES_ISA_COUNT - 1;
static pthread_once_t env_once = PTHREAD_ONCE_INIT;
static lanes_status env_status = LANES_OK;
static char env_message[384];

static void set_message(char *message, size_t size, const char *text)
{
    if (message && size) snprintf(message, size, "%s", text);
}

static lanes_isa best_below(int cap)
{
    for (int i = cap; i >= 0; i--)
        if (i != LANES_ISA_AVX512EMU && lanes_isa_supported((lanes_isa)i)) return (lanes_isa)i;
    return LANES_ISA_SCALAR;
}

lanes_isa lanes_isa_best(void) { return best_below(atomic_load(&max_isa)); }

/* Why a set cannot run here, naming the missing features at the first level
 * that lacks one (CPU, then OS, then the disable switch). */
lanes_status lanes_isa_check(lanes_isa isa, char *why, size_t size)
{
    if (!valid(isa)) {
        snprintf(why, size, "unknown instruction set; valid names: %s", lanes_isa_all_names());
        return LANES_ERR_UNKNOWN_ISA;
    }
    if (!isa_compiled[isa]) {
        snprintf(why, size, "instruction set '%s' was not compiled into this build (see LANES_ISAS)",
                 isa_names[isa]);
        return LANES_ERR_NOT_COMPILED;
    }
    char reason[160];
    if (lanes_cpu_explain_missing(lanes_cpu(), isa_needs[isa], reason, sizeof reason)) {
        snprintf(why, size, "instruction set '%s' cannot run on this CPU: %s", isa_names[isa],
                 reason);
        return LANES_ERR_CPU_LACKS;
    }
    return LANES_OK;
}

static void read_environment(void)
{
    const char *cap = getenv("LANES_MAX_ISA");
    const char *force = getenv("LANES_ISA");
    char why[240];
    lanes_isa chosen = LANES_ISA_NONE;

    const char *unknown = lanes_cpu()->unknown_disabled;
    if (unknown[0]) {
        env_status = LANES_ERR_BAD_INPUT;
        snprintf(env_message, sizeof env_message,
                 "LANES_DISABLE_CPU_FEATURES: '%s' is not a CPU feature; valid names: %s", unknown,
                 lanes_cpu_all_feature_names());
    }
    if (env_status == LANES_OK && cap && *cap) {
        lanes_isa c = lanes_isa_from_name(cap);
        if (c == LANES_ISA_NONE) {
            env_status = LANES_ERR_UNKNOWN_ISA;
            snprintf(env_message, sizeof env_message,
                     "LANES_MAX_ISA=%s: unknown instruction set; valid names: %s", cap,
                     lanes_isa_all_names());
        } else {
            atomic_store(&max_isa, c);
        }
    }
    if (env_status == LANES_OK && force && *force) {
        lanes_isa f = lanes_isa_from_name(force);
        lanes_status st = lanes_isa_check(f, why, sizeof why);
        if (st != LANES_OK) {
            env_status = st;
            if (f == LANES_ISA_NONE)
                snprintf(env_message, sizeof env_message, "LANES_ISA=%s: %s", force, why);
            else
                snprintf(env_message, sizeof env_message, "LANES_ISA: %s", why);
        } else {
            chosen = f;
        }
    }
    if (chosen == LANES_ISA_NONE) chosen = lanes_isa_best();
    /* An API call that raced ahead of us keeps its choice. */
    int expected = LANES_ISA_NONE;
    atomic_compare_exchange_strong(&current_isa, &expected, (int)chosen);
}

lanes_status lanes_isa_init(char *message, size_t message_size)
{
    pthread_once(&env_once, read_environment);
    set_message(message, message_size, env_message);
    return env_status;
}

lanes_isa lanes_isa_current(void)
{
    pthread_once(&env_once, read_environment);
    return (lanes_isa)atomic_load(&current_isa);
}

lanes_status lanes_set_isa(lanes_isa isa, char *message, size_t message_size)
{
    char why[240];
    pthread_once(&env_once, read_environment);
    if (isa == LANES_ISA_NONE) {
        atomic_store(&current_isa, (int)lanes_isa_best());
        set_message(message, message_size, "");
        return LANES_OK;
    }
    lanes_status st = lanes_isa_check(isa, why, sizeof why);
    set_message(message, message_size, st == LANES_OK ? "" : why);
    if (st == LANES_OK) atomic_store(&current_isa, (int)isa);
    return st;
}

lanes_status lanes_set_isa_by_name(const char *name, char *message, size_t message_size)
{
    lanes_isa isa = lanes_isa_from_name(name);
    if (isa == LANES_ISA_NONE) {
        if (message && message_size)
            snprintf(message, message_size, "'%s' is not an instruction set; valid names: %s",
                     name ? name : "(null)", lanes_isa_all_names());
        return LANES_ERR_UNKNOWN_ISA;
    }
    return lanes_set_isa(isa, message, message_size);
}

lanes_status lanes_set_max_isa(lanes_isa cap, char *message, size_t message_size)
{
    pthread_once(&env_once, read_environment);
    if (!valid(cap)) {
        set_message(message, message_size, "unknown instruction set");
        return LANES_ERR_UNKNOWN_ISA;
    }
    atomic_store(&max_isa, (int)cap);
    atomic_store(&current_isa, (int)lanes_isa_best());
    set_message(message, message_size, "");
    return LANES_OK;
}
