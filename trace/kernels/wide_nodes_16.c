/* The wide-BVH kernels of this set for 16-wide nodes (see wide_variant.h). */
#define LANES_VARIANT_WIDTH 16
#define LANES_WIDE_TAG _w16
#include "trace/kernels/wide_variant.h"
