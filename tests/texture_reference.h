/* The solid textures of trace/texture.h in double precision, from the
 * construction trace/kernels/texture_core.h describes (same lattice hash,
 * gradients, blend and octaves), for tests/test_textures.c. */
#ifndef LANES_TESTS_TEXTURE_REFERENCE_H
#define LANES_TESTS_TEXTURE_REFERENCE_H

#include "trace/texture.h"

/* The noise before its scale and clamp. */
double ref_noise_raw(double x, double y, double z);
double ref_noise(double x, double y, double z);
/* The blend weight at a point already divided by the texture's scale. */
double ref_texture_weight(lanes_texture_kind kind, double x, double y, double z);

#endif
