/* Between test_textures.c (baseline driver) and test_textures_set.c
 * (compiled once per kernel set): trace/kernels/texture_core.h over
 * arrays of n points (n a multiple of 16). */
#ifndef LANES_TESTS_TEST_TEXTURES_H
#define LANES_TESTS_TEST_TEXTURES_H

#include <stddef.h>

#include "trace/texture.h"

#ifdef LANES_FN
void LANES_FN(test_noise)(size_t n, const float *x, const float *y, const float *z, float *out);
/* The texture's blend weight and color (SoA, stride n) at scene points. */
void LANES_FN(test_texture)(const lanes_texture *t, size_t n, const float *x, const float *y, const float *z,
                            float *weight, float *color);
#endif

#endif
