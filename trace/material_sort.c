/* Grouping a ray stream by material (see material_sort.h). */
#include "trace/material_sort.h"

lanes_status lanes_sort_by_material(const uint32_t *material, size_t n, uint32_t material_count,
                                    uint32_t *offsets, uint32_t *sorted, lanes_error *err)
{
    if (material_count == 0 || material_count > LANES_SORT_MAX_MATERIALS)
        return lanes_error_set(err, LANES_ERR_BAD_INPUT,
                               "material sort: %u materials (the sort takes 1 to %u)", material_count,
                               LANES_SORT_MAX_MATERIALS);
    if (n > UINT32_MAX)
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "material sort: %zu rays (at most %u in a stream)", n,
                               UINT32_MAX);
    for (uint32_t m = 0; m <= material_count; m++) offsets[m] = 0;
    /* histogram one slot ahead, so the prefix sum leaves each material's start */
    for (size_t i = 0; i < n; i++) {
        if (material[i] >= material_count)
            return lanes_error_set(err, LANES_ERR_BAD_INPUT, "material sort: ray %zu has material %u of %u", i,
                                   material[i], material_count);
        offsets[material[i] + 1]++;
    }
    for (uint32_t m = 0; m < material_count; m++) offsets[m + 1] += offsets[m];
    /* forwards, so that each material keeps its slots in order (stable) */
    for (size_t i = 0; i < n; i++) sorted[offsets[material[i]]++] = (uint32_t)i;
    /* the scatter moved each start to where the next material begins */
    for (uint32_t m = material_count; m > 0; m--) offsets[m] = offsets[m - 1];
    offsets[0] = 0;
    return LANES_OK;
}

double lanes_sorted_shading_utilization(const uint32_t *offsets, uint32_t material_count, int lanes)
{
    uint64_t rays = 0, slots = 0;
    for (uint32_t m = 0; m < material_count; m++) {
        uint64_t k = offsets[m + 1] - offsets[m];
        rays += k;
        slots += (k + (uint64_t)lanes - 1) / (uint64_t)lanes * (uint64_t)lanes;
    }
    return slots ? (double)rays / (double)slots : 1.0;
}
