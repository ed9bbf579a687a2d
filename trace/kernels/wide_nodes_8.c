/* The wide-BVH kernels of this set for 8-wide nodes (see wide_variant.h). */
#define LANES_VARIANT_WIDTH 8
#define LANES_WIDE_TAG _w8
#include "trace/kernels/wide_variant.h"
