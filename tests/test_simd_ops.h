/* The interface between test_simd_ops.c (the baseline driver) and
 * test_simd_ops_set.c (compiled once per kernel set). The per-set code only
 * computes and compares; reporting, counting and the guard pages live in
 * the driver, which is compiled for the x86-64 baseline. */
#ifndef LANES_TESTS_TEST_SIMD_OPS_H
#define LANES_TESTS_TEST_SIMD_OPS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef struct simd_ctx {
    const char *isa;  /* the set being tested */
    const char *op;   /* the operation being tested */
    long op_fails;
    long passed, failed, skipped; /* (set, op) groups */
    int max_print;
    uint64_t seed;
    /* The last floats of a readable and writable page; the next page is
     * inaccessible. Masked loads and stores and compress stores there must
     * not touch the inactive lanes' memory. */
    float *page_end;
    size_t page_floats;
} simd_ctx;

/* Begin and end a (set, op) group; failures in between are counted, the
 * first max_print of each group printed. */
void simd_begin(simd_ctx *c, const char *op);
void simd_fail(simd_ctx *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
void simd_end(simd_ctx *c);

/* test_simd_ops_run_<set>(simd_ctx *c): one per compiled set, defined by
 * test_simd_ops_set.c with the set's suffix (declared in test_simd_ops.c
 * from the generated list of sets). */
#ifdef LANES_FN
void LANES_FN(test_simd_ops_run)(simd_ctx *c);
/* In test_simd_math_set.c: simd/vmath.h and simd/vrandom.h. */
void LANES_FN(test_simd_math_run)(simd_ctx *c);
#endif

#endif
