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

/* The generated list of the sets this build compiled (CMake writes it from
 * LANES_ISAS and what the compiler could build). */
#include "lanes_built_sets.h"

typedef struct isa_row {
    const char *name, *family;
    int lanes, rank;
    bool emulated, automatic;
    uint32_t needs;
} isa_row;

static const isa_row rows[LANES_ISA_COUNT] = {
#define ROW(id, nm, ln, fam, emu, rk, au, nd) [LANES_ISA_##id] = {#nm, #fam, ln, rk, emu, au, nd},
    LANES_KERNEL_SETS(ROW)
#undef ROW
};

static const bool isa_compiled[LANES_ISA_COUNT] = {
#define BUILT(id, name) [LANES_ISA_##id] = true,
    LANES_BUILT_SETS(BUILT)
#undef BUILT
};

static bool valid(lanes_isa isa) { return isa >= 0 && isa < LANES_ISA_COUNT; }

const char *lanes_isa_name(lanes_isa isa) { return valid(isa) ? rows[isa].name : "none"; }
int lanes_isa_lanes(lanes_isa isa) { return valid(isa) ? rows[isa].lanes : 0; }
const char *lanes_isa_family(lanes_isa isa) { return valid(isa) ? rows[isa].family : "none"; }
bool lanes_isa_emulated(lanes_isa isa) { return valid(isa) && rows[isa].emulated; }
bool lanes_isa_automatic(lanes_isa isa) { return valid(isa) && rows[isa].automatic; }
uint32_t lanes_isa_required_features(lanes_isa isa) { return valid(isa) ? rows[isa].needs : 0; }
bool lanes_isa_compiled(lanes_isa isa) { return valid(isa) && isa_compiled[isa]; }

bool lanes_isa_cpu_can_run(lanes_isa isa)
{
    return valid(isa) && (lanes_cpu()->bits & rows[isa].needs) == rows[isa].needs;
}

bool lanes_isa_supported(lanes_isa isa) { return lanes_isa_compiled(isa) && lanes_isa_cpu_can_run(isa); }

lanes_isa lanes_isa_from_name(const char *name)
{
    for (int i = 0; name && i < LANES_ISA_COUNT; i++)
        if (strcmp(name, rows[i].name) == 0) return (lanes_isa)i;
    return LANES_ISA_NONE;
}

/* Derived once from the table: the names for messages and the order of
 * preference. */
static pthread_once_t derived_once = PTHREAD_ONCE_INIT;
static char all_names[LANES_ISA_COUNT * 16];
static lanes_isa ranked[LANES_ISA_COUNT];

static void derive(void)
{
    size_t used = 0;
    for (int i = 0; i < LANES_ISA_COUNT; i++) {
        int n = snprintf(all_names + used, sizeof all_names - used, "%s%s", i ? ", " : "", rows[i].name);
        if (n > 0 && (size_t)n < sizeof all_names - used) used += (size_t)n;
        ranked[i] = (lanes_isa)i;
    }
    for (int i = 1; i < LANES_ISA_COUNT; i++) /* insertion sort, best rank first */
        for (int j = i; j > 0 && rows[ranked[j]].rank > rows[ranked[j - 1]].rank; j--) {
            lanes_isa t = ranked[j];
            ranked[j] = ranked[j - 1];
            ranked[j - 1] = t;
        }
}

const char *lanes_isa_all_names(void)
{
    pthread_once(&derived_once, derive);
    return all_names;
}

const lanes_isa *lanes_isa_ranked(void)
{
    pthread_once(&derived_once, derive);
    return ranked;
}

/* The active set and the cap, as atomics: read on every kernel-table lookup. */
static _Atomic int current_isa = LANES_ISA_NONE;
static _Atomic int max_isa = LANES_ISA_NONE; /* NONE: no cap */
static pthread_once_t env_once = PTHREAD_ONCE_INIT;
static lanes_status env_status = LANES_OK;
static char env_message[384];

/* The calling thread's last failure, for lanes_last_error_message: kept
 * here, in the lowest layer, so that the process-wide set choice below and
 * the device and accel API (trace/lanes_api.c) report through one place. */
static _Thread_local char last_error[512];

LANES_API const char *lanes_last_error_message(void) { return last_error; }

void lanes_record_error(const char *text) { snprintf(last_error, sizeof last_error, "%s", text); }

/* The caller's message buffer gets text; a failure is also the thread's
 * last error. */
static lanes_status report(lanes_status status, char *message, size_t size, const char *text)
{
    if (message && size) snprintf(message, size, "%s", text);
    if (status != LANES_OK) lanes_record_error(text);
    return status;
}

/* The best-ranked automatic set the build has and the CPU runs, ranked at
 * most as high as the cap. */
static lanes_isa best_below(lanes_isa cap)
{
    const lanes_isa *order = lanes_isa_ranked();
    for (int i = 0; i < LANES_ISA_COUNT; i++) {
        lanes_isa isa = order[i];
        if (valid(cap) && rows[isa].rank > rows[cap].rank) continue;
        if (rows[isa].automatic && lanes_isa_supported(isa)) return isa;
    }
    return LANES_ISA_SCALAR;
}

lanes_isa lanes_isa_best(void) { return best_below((lanes_isa)atomic_load(&max_isa)); }

/* Why a set cannot run here, naming the missing features at the first level
 * that lacks one (CPU, then OS, then the disable switch). */
lanes_status lanes_isa_check(lanes_isa isa, char *why, size_t size)
{
    char text[240];
    if (!valid(isa)) {
        snprintf(text, sizeof text, "unknown instruction set; valid names: %s", lanes_isa_all_names());
        return report(LANES_ERR_UNKNOWN_ISA, why, size, text);
    }
    if (!isa_compiled[isa]) {
        snprintf(text, sizeof text, "instruction set '%s' was not compiled into this build (see LANES_ISAS)",
                 rows[isa].name);
        return report(LANES_ERR_NOT_COMPILED, why, size, text);
    }
    char reason[160];
    if (lanes_cpu_explain_missing(lanes_cpu(), rows[isa].needs, reason, sizeof reason)) {
        snprintf(text, sizeof text, "instruction set '%s' cannot run on this CPU: %s", rows[isa].name,
                 reason);
        return report(LANES_ERR_CPU_LACKS, why, size, text);
    }
    return report(LANES_OK, why, size, "");
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
    return report(env_status, message, message_size, env_message);
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
        return report(LANES_OK, message, message_size, "");
    }
    lanes_status st = lanes_isa_check(isa, why, sizeof why);
    if (st == LANES_OK) atomic_store(&current_isa, (int)isa);
    return report(st, message, message_size, st == LANES_OK ? "" : why);
}

lanes_status lanes_set_isa_by_name(const char *name, char *message, size_t message_size)
{
    lanes_isa isa = lanes_isa_from_name(name);
    if (isa == LANES_ISA_NONE) {
        char why[384];
        snprintf(why, sizeof why, "'%s' is not an instruction set; valid names: %s",
                 name ? name : "(null)", lanes_isa_all_names());
        return report(LANES_ERR_UNKNOWN_ISA, message, message_size, why);
    }
    return lanes_set_isa(isa, message, message_size);
}

lanes_status lanes_set_max_isa(lanes_isa cap, char *message, size_t message_size)
{
    pthread_once(&env_once, read_environment);
    if (!valid(cap)) {
        char why[384];
        snprintf(why, sizeof why, "lanes_set_max_isa: unknown instruction set %d; valid names: %s",
                 (int)cap, lanes_isa_all_names());
        return report(LANES_ERR_UNKNOWN_ISA, message, message_size, why);
    }
    atomic_store(&max_isa, (int)cap);
    atomic_store(&current_isa, (int)lanes_isa_best());
    return report(LANES_OK, message, message_size, "");
}
