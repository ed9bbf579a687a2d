/* The shading side of ray streams (Afra, Benthin, Wald and Munkberg 2016):
 * a stream's rays, grouped by the material they hit so that each shading
 * batch runs one shader on full vectors, and what that grouping buys.
 *
 * Baseline code: sorting is no per-width work. */
#ifndef LANES_TRACE_MATERIAL_SORT_H
#define LANES_TRACE_MATERIAL_SORT_H

#include <stddef.h>
#include <stdint.h>

#include "build/error.h"

/* The sort keeps per-material offsets in 32 bits and a histogram of this
 * many entries per thread; scenes with more materials are refused. */
#define LANES_SORT_MAX_MATERIALS 65536u

/* A stable counting sort of the slots 0 .. n-1 by material[slot] (each
 * below material_count): sorted[] receives the slots, those of material 0
 * first, each material's in increasing slot order; offsets[m] ..
 * offsets[m+1] is material m's range (material_count + 1 entries). Two
 * passes over material[], none over the rays themselves. Refuses, with
 * LANES_ERR_BAD_INPUT and a message, a material_count of 0 or above
 * LANES_SORT_MAX_MATERIALS, n of 2^32 or more, and a material out of range
 * (sorted[] and offsets[] are then left undefined). */
lanes_status lanes_sort_by_material(const uint32_t *material, size_t n, uint32_t material_count,
                                    uint32_t *offsets, uint32_t *sorted, lanes_error *err);

/* The SIMD utilisation of shading the sorted stream in batches of `lanes`
 * (the paper's measure): the rays over the lane slots they occupy, each
 * material's n_m rays taking ceil(n_m / lanes) full vectors,
 * sum n_m / sum lanes * ceil(n_m / lanes). 1 for an empty stream. */
double lanes_sorted_shading_utilization(const uint32_t *offsets, uint32_t material_count, int lanes);

#endif
