/* Between test_bsdf.c (baseline driver) and test_bsdf_set.c (compiled once
 * per kernel set): the BSDFs of trace/kernels/bsdf_core.h over arrays.
 * Directions are SoA with stride n (x[0..n), y[n..2n), z[2n..3n)); n is a
 * multiple of 16. */
#ifndef LANES_TESTS_TEST_BSDF_H
#define LANES_TESTS_TEST_BSDF_H

#include <stddef.h>
#include <stdint.h>

#include "trace/bsdf.h"

enum { TEST_BSDF_VALID = 1, TEST_BSDF_DELTA = 2 };

#ifdef LANES_FN
void LANES_FN(test_bsdf_eval)(const lanes_bsdf *b, size_t n, const float *wo, const float *wi, float *f, float *pdf);
/* u: three numbers per direction, SoA like the directions. */
void LANES_FN(test_bsdf_sample)(const lanes_bsdf *b, size_t n, const float *wo, const float *u, float *wi,
                                float *weight, float *pdf, uint8_t *flags);
#endif

#endif
