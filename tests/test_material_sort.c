/* The stream's material sort and its shading utilisation
 * (trace/material_sort.c): the sort against a stable qsort by (material,
 * slot), on streams of every shape (one material, all distinct, skewed,
 * empty, the largest material count); every slot once; the utilisation
 * against a recount from each material's rays; the refusals. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "trace/material_sort.h"

static const uint32_t *sort_keys;

/* qsort is not stable: the slot breaks ties, which is what stability means here. */
static int by_material_then_slot(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    if (sort_keys[x] != sort_keys[y]) return sort_keys[x] < sort_keys[y] ? -1 : 1;
    return x < y ? -1 : x > y;
}

/* Utilisation recounted from a histogram of the stream itself. */
static double recount(const uint32_t *material, size_t n, uint32_t count, int lanes)
{
    long *hist = calloc(count, sizeof *hist);
    if (!hist) return -1.0;
    for (size_t i = 0; i < n; i++) hist[material[i]]++;
    double rays = 0.0, slots = 0.0;
    for (uint32_t m = 0; m < count; m++) {
        rays += (double)hist[m];
        long vectors = hist[m] / lanes + (hist[m] % lanes != 0);
        slots += (double)(vectors * lanes);
    }
    free(hist);
    return slots > 0.0 ? rays / slots : 1.0;
}

static void check_stream(const char *what, const uint32_t *material, size_t n, uint32_t count)
{
    uint32_t *offsets = malloc((count + 1) * sizeof *offsets);
    uint32_t *sorted = malloc((n + 1) * sizeof *sorted), *want = malloc((n + 1) * sizeof *want);
    if (!offsets || !sorted || !want) {
        harness_fail("%s: out of memory", what);
        return;
    }
    lanes_error err;
    if (CHECK(lanes_sort_by_material(material, n, count, offsets, sorted, &err) == LANES_OK, "%s: %s", what,
              err.message)) {
        for (size_t i = 0; i < n; i++) want[i] = (uint32_t)i;
        sort_keys = material;
        qsort(want, n, sizeof *want, by_material_then_slot);
        CHECK(n == 0 || memcmp(sorted, want, n * sizeof *want) == 0, "%s: the order differs from a stable sort", what);
        bool ranges = offsets[0] == 0 && offsets[count] == n;
        for (uint32_t m = 0; m < count && ranges; m++)
            for (uint32_t k = offsets[m]; k < offsets[m + 1] && ranges; k++) ranges = material[sorted[k]] == m;
        CHECK(ranges, "%s: offsets do not bound each material's slots", what);
        static const int widths[] = {1, 4, 8, 16};
        for (int w = 0; w < 4; w++) {
            double got = lanes_sorted_shading_utilization(offsets, count, widths[w]);
            double expect = recount(material, n, count, widths[w]);
            CHECK(got == expect, "%s: utilisation at %d lanes %.6f, recount %.6f", what, widths[w], got, expect);
        }
    }
    free(offsets), free(sorted), free(want);
}

int main(void)
{
    enum { N = 2048 };
    static uint32_t material[1 << 17];
    harness_rng r = harness_rng_seed(2016);

    for (size_t i = 0; i < N; i++) material[i] = 0;
    check_stream("one material", material, N, 1);
    for (size_t i = 0; i < N; i++) material[i] = (uint32_t)(harness_next(&r) % 111);
    check_stream("111 materials, uniform", material, N, 111);
    for (size_t i = 0; i < N; i++) {
        double u = harness_uniform(&r);
        material[i] = (uint32_t)(u * u * u * 36.0); /* skewed: most rays on a few */
    }
    check_stream("36 materials, skewed", material, N, 36);
    for (size_t i = 0; i < N; i++) material[i] = (uint32_t)(N - 1 - i);
    check_stream("every ray its own material, reversed", material, N, N);
    check_stream("empty stream", material, 0, 5);
    for (size_t i = 0; i < (1u << 17); i++) material[i] = (uint32_t)(harness_next(&r) % LANES_SORT_MAX_MATERIALS);
    check_stream("65536 materials, 131072 rays", material, 1u << 17, LANES_SORT_MAX_MATERIALS);

    /* utilisation by hand: 5 rays of one material and 3 of another at 4
     * lanes fill 8 of 12 slots */
    uint32_t offsets[3] = {0, 5, 8};
    CHECK(lanes_sorted_shading_utilization(offsets, 2, 4) == 8.0 / 12.0, "5 + 3 rays at 4 lanes: %g",
          lanes_sorted_shading_utilization(offsets, 2, 4));

    /* refusals, with the reason */
    uint32_t out[4], offs[LANES_SORT_MAX_MATERIALS + 2];
    lanes_error err;
    uint32_t bad[4] = {0, 1, 7, 2};
    CHECK(lanes_sort_by_material(bad, 4, 3, offs, out, &err) == LANES_ERR_BAD_INPUT && strstr(err.message, "ray 2"),
          "a material out of range: %s", err.message);
    CHECK(lanes_sort_by_material(bad, 4, 0, offs, out, &err) == LANES_ERR_BAD_INPUT && strstr(err.message, "0 materials"),
          "no materials: %s", err.message);
    CHECK(lanes_sort_by_material(bad, 4, LANES_SORT_MAX_MATERIALS + 1, offs, out, &err) == LANES_ERR_BAD_INPUT &&
              strstr(err.message, "65537 materials"),
          "65537 materials: %s", err.message);
    return harness_summary("test_material_sort");
}
