/* Tests of the SIMD layer itself (simd/vec*.h through simd/simd.h), one run
 * per kernel set this CPU can execute; the others are reported as skipped.
 *
 *   test_simd_ops [--isa a,b,...] [--seed N] [--print N]
 *
 * The last line is "N passed, N failed, N skipped": passed and failed
 * count (set, op) groups, skipped counts the sets not run (each would have
 * been a couple of dozen groups). The exit status is 1 when any failed. */
#define _DEFAULT_SOURCE /* MAP_ANONYMOUS */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "simd/isa.h"
#include "name_list.h"
#include "test_simd_ops.h"

void simd_begin(simd_ctx *c, const char *op)
{
    c->op = op;
    c->op_fails = 0;
}

void simd_fail(simd_ctx *c, const char *fmt, ...)
{
    if (c->op_fails++ < c->max_print) {
        va_list ap;
        va_start(ap, fmt);
        printf("  FAIL %s %s: ", c->isa, c->op);
        vprintf(fmt, ap);
        printf("\n");
        va_end(ap);
    }
}

void simd_end(simd_ctx *c)
{
    if (c->op_fails) {
        printf("FAIL %s %s [%ld failures]\n", c->isa, c->op, c->op_fails);
        c->failed++;
    } else {
        c->passed++;
    }
}

typedef void (*run_fn)(simd_ctx *);

#include "test_simd_ops_set_sets.h" /* the sets built: TEST_SIMD_OPS_SET_SETS (generated) */

#define DECLARE(id, name) void test_simd_ops_run_##name(simd_ctx *c);
TEST_SIMD_OPS_SET_SETS(DECLARE)
#undef DECLARE

static const run_fn runs[LANES_ISA_COUNT] = {
#define ENTRY(id, name) [LANES_ISA_##id] = test_simd_ops_run_##name,
    TEST_SIMD_OPS_SET_SETS(ENTRY)
#undef ENTRY
};


int main(int argc, char **argv)
{
    simd_ctx c;
    memset(&c, 0, sizeof c);
    c.max_print = 10;
    c.seed = 20240601;
    const char *isa_list = NULL;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--isa") == 0 && i + 1 < argc) {
            isa_list = argv[++i];
        } else if (strcmp(argv[i], "--seed") == 0 && i + 1 < argc) {
            c.seed = strtoull(argv[++i], NULL, 0);
        } else if (strcmp(argv[i], "--print") == 0 && i + 1 < argc) {
            c.max_print = atoi(argv[++i]);
        } else if (strcmp(argv[i], "--quick") == 0) {
            /* accepted for symmetry with test_kernels: this test is quick */
        } else {
            fprintf(stderr, "usage: %s [--isa a,b,...] [--seed N] [--print N]\n  sets: %s\n", argv[0],
                    lanes_isa_all_names());
            return 2;
        }
    }
    /* two pages, the second inaccessible */
    long pg = sysconf(_SC_PAGESIZE);
    if (pg <= 0) pg = 4096;
    char *mem = mmap(NULL, 2 * (size_t)pg, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (mem == MAP_FAILED || mprotect(mem + pg, (size_t)pg, PROT_NONE) != 0) {
        perror("test_simd_ops: guard page");
        return 2;
    }
    c.page_end = (float *)(void *)(mem + pg);
    c.page_floats = (size_t)pg / sizeof(float);

    const lanes_cpu_features *cpu = lanes_cpu();
    printf("test_simd_ops: CPU %s (%s)\n", cpu->brand, cpu->vendor);
    for (int i = 0; i < LANES_ISA_COUNT; i++) {
        lanes_isa isa = (lanes_isa)i;
        const char *name = lanes_isa_name(isa);
        if (!harness_in_list(isa_list, name)) {
            printf("SKIP %s: not selected by --isa\n", name);
            c.skipped++;
        } else if (!runs[i] || !lanes_isa_compiled(isa)) {
            printf("SKIP %s: not compiled into this build (LANES_ISAS)\n", name);
            c.skipped++;
        } else if (!lanes_isa_cpu_can_run(isa)) {
            char list[160] = "";
            lanes_cpu_feature_list(lanes_isa_required_features(isa) & ~cpu->bits, list, sizeof list);
            printf("SKIP %s: this CPU (or OS) lacks %s\n", name, list);
            c.skipped++;
        } else {
            long before_p = c.passed, before_f = c.failed;
            c.isa = name;
            runs[i](&c);
            printf("%s %s SIMD layer (%ld ops passed, %ld failed)\n", c.failed > before_f ? "FAIL" : "PASS", name,
                   c.passed - before_p, c.failed - before_f);
        }
    }
    munmap(mem, 2 * (size_t)pg);
    printf("%ld passed, %ld failed, %ld skipped\n", c.passed, c.failed, c.skipped);
    return c.failed ? 1 : 0;
}
