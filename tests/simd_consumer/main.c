/* The baseline side of an outside project's width-generic kernel: one table
 * entry per kernel set its build compiled (the list lanes_add_kernel_sets
 * writes), each set it can run checked against plain C, then
 * the set lanes chooses for this CPU dispatched. Compiled without any -m
 * flag: only the kernel objects hold the sets' instructions. */
#include <lanes/lanes.h>

#include <stdio.h>
#include <string.h>

/* consumer_kernels_sets.h, written by lanes_add_kernel_sets: the sets
 * this build compiled, as CONSUMER_KERNELS_SETS(X) = X(ID, name) ... */
#include "consumer_kernels_sets.h"

#define DECLARE(id, set)                                                                   \
    int consumer_lanes_##set(void);                                                       \
    size_t consumer_count_below_and_scale_##set(float *x, size_t n, float threshold, float scale);
CONSUMER_KERNELS_SETS(DECLARE)
#undef DECLARE

typedef struct kernel_set {
    lanes_isa isa;
    int (*lanes)(void);
    size_t (*count_below_and_scale)(float *x, size_t n, float threshold, float scale);
} kernel_set;

#define ENTRY(id, set) {LANES_ISA_##id, consumer_lanes_##set, consumer_count_below_and_scale_##set},
static const kernel_set sets[] = {CONSUMER_KERNELS_SETS(ENTRY)};
#undef ENTRY
enum { N = 1037, SETS = sizeof sets / sizeof sets[0] };

static int passed, failed;

static void check(int ok, const char *what, const char *set)
{
    ok ? passed++ : failed++;
    printf("%s %s: %s\n", ok ? "PASS" : "FAIL", set, what);
}

int main(void)
{
    float input[N], want[N], got[N];
    size_t want_below = 0;
    for (int i = 0; i < N; i++) {
        input[i] = (float)((i * 7919) % 1000) / 100.0f - 5.0f;
        want[i] = input[i] < 1.5f ? (want_below++, input[i]) : input[i] * 0.75f;
    }
    for (int s = 0; s < SETS; s++) {
        const char *name = lanes_isa_name(sets[s].isa);
        if (!lanes_isa_cpu_can_run(sets[s].isa)) {
            printf("SKIP %s: this CPU cannot run it\n", name);
            continue;
        }
        check(sets[s].lanes() == lanes_isa_lanes(sets[s].isa), "LANES_W is the set's width", name);
        memcpy(got, input, sizeof got);
        size_t below = sets[s].count_below_and_scale(got, N, 1.5f, 0.75f);
        check(below == want_below && memcmp(got, want, sizeof got) == 0, "the kernel's results", name);
    }
    /* Dispatch: the set lanes chooses here (LANES_ISA and LANES_MAX_ISA
     * honoured), if this build has it. */
    lanes_isa chosen = lanes_isa_current();
    const kernel_set *k = NULL;
    for (int s = 0; s < SETS; s++)
        if (sets[s].isa == chosen) k = &sets[s];
    if (k) {
        memcpy(got, input, sizeof got);
        size_t below = k->count_below_and_scale(got, N, 1.5f, 0.75f);
        printf("dispatched to %s (%d lanes)\n", lanes_isa_name(chosen), k->lanes());
        check(below == want_below && memcmp(got, want, sizeof got) == 0, "dispatched", lanes_isa_name(chosen));
    } else {
        printf("the chosen set %s was not built here\n", lanes_isa_name(chosen));
    }
    printf("%d passed, %d failed\n", passed, failed);
    return failed || passed == 0 ? 1 : 0;
}
