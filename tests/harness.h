/* The tests' harness: checks that count and report, the summary line and
 * exit status, and seeded random numbers.
 *
 *   CHECK(cond, fmt, ...)   counts a check; when cond is false, counts a
 *                           failure and prints "FAIL file:line: message"
 *                           (the first harness.max_print of them); yields
 *                           cond, so `if (!CHECK(...)) continue;` reads.
 *   harness_fail(fmt, ...)  a failure found without a condition to hand.
 *   harness_skip()          a check that could not run here (a set the CPU
 *                           lacks): counted, and said in the summary.
 *   harness_summary(name)   "name: 12 checks, 0 failed" (and skipped); the
 *                           exit status for main: 1 when anything failed.
 *   harness_rng             splitmix64: the same numbers on every machine.
 *   harness_in_list(l, n)   n is in the comma-separated list l (NULL: all;
 *                           name_list.h).
 *
 * One translation unit per test program: the counters are static. */
#ifndef LANES_TESTS_HARNESS_H
#define LANES_TESTS_HARNESS_H

#include "name_list.h"

#include <stdarg.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#if defined(__GNUC__)
#define HARNESS_PRINTF(f, a) __attribute__((format(printf, f, a)))
#else
#define HARNESS_PRINTF(f, a)
#endif

static struct {
    long checks, failures, skipped;
    long max_print; /* failures printed in full; the rest only counted */
} harness = {0, 0, 0, 50};

static inline void harness_vreport(const char *file, int line, const char *fmt, va_list ap)
{
    if (harness.failures > harness.max_print) return;
    printf("FAIL %s:%d: ", file, line);
    vprintf(fmt, ap);
    printf("\n");
    if (harness.failures == harness.max_print) printf("(further failures are counted, not printed)\n");
    fflush(stdout);
}

static inline bool harness_check(bool ok, const char *file, int line, const char *fmt, ...) HARNESS_PRINTF(4, 5);
static inline bool harness_check(bool ok, const char *file, int line, const char *fmt, ...)
{
    harness.checks++;
    if (ok) return true;
    harness.failures++;
    va_list ap;
    va_start(ap, fmt);
    harness_vreport(file, line, fmt, ap);
    va_end(ap);
    return false;
}

#define CHECK(cond, ...) harness_check((cond) ? true : false, __FILE__, __LINE__, __VA_ARGS__)

static inline void harness_fail_at(const char *file, int line, const char *fmt, ...) HARNESS_PRINTF(3, 4);
static inline void harness_fail_at(const char *file, int line, const char *fmt, ...)
{
    harness.checks++;
    harness.failures++;
    va_list ap;
    va_start(ap, fmt);
    harness_vreport(file, line, fmt, ap);
    va_end(ap);
}

#define harness_fail(...) harness_fail_at(__FILE__, __LINE__, __VA_ARGS__)

static inline void harness_skip(void)
{
    harness.skipped++;
}

static inline int harness_summary(const char *name)
{
    printf("%s: %ld checks, %ld failed", name, harness.checks, harness.failures);
    if (harness.skipped) printf(", %ld skipped", harness.skipped);
    printf("\n");
    return harness.failures ? 1 : 0;
}

typedef struct harness_rng {
    uint64_t state;
} harness_rng;

static inline harness_rng harness_rng_seed(uint64_t seed)
{
    return (harness_rng){seed};
}

static inline uint64_t harness_next(harness_rng *r)
{
    uint64_t z = (r->state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/* Uniform in [0, 1), 53 random bits. */
static inline double harness_uniform(harness_rng *r)
{
    return (double)(harness_next(r) >> 11) * 0x1p-53;
}


#endif
