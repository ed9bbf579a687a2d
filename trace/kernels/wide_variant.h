/* The kernels that read a wide BVH (single-ray, hybrid and stream
 * traversal: LANES_KERNELS_WIDE_BVH) compiled again for a node width wider
 * than the set's own, so that every set traverses trees of every node width
 * from its lane count up, a node's children tested in width / LANES_W
 * vectors: the sse4 set on 8- and 16-wide nodes, avx2 on 16-wide ones, and
 * the 16 lanes of avx512 beside the 8 of avx512vl8 on the same 16-wide tree.
 *
 * Included by wide_nodes_<width>.c, which defines LANES_VARIANT_WIDTH and
 * LANES_WIDE_TAG (_w<width>) first. Defines the table
 * lanes_wide_kernels_w<width>_<set>, which kernels_dispatch.c lays over the
 * set's own (lanes_kernels_for_width); its width is 0 when the set has no
 * such variant (its own width, or one narrower than its lanes). The entry
 * points carry the tag in their names (kernel_decls.h). */
#ifndef LANES_TRACE_WIDE_VARIANT_H
#define LANES_TRACE_WIDE_VARIANT_H

#include "simd/simd.h"

/* wider than the set's own (kernel_common.h) */
#if LANES_VARIANT_WIDTH > (LANES_W == 1 ? 4 : LANES_W)
#define LANES_WIDE_WIDTH LANES_VARIANT_WIDTH
/* The families' files, each a whole kernel family for this width; their
 * helpers are static inline and named apart, so one unit holds all three. */
#include "trace/kernels/traverse_kernels.c"
#include "trace/kernels/hybrid_kernels.c"
#include "trace/kernels/stream_kernels.c"

const lanes_wide_kernels LANES_KFN(lanes_wide_kernels) = {
    .width = LANES_WIDE_WIDTH,
    LANES_KERNELS_WIDE_BVH(LANES_KERNEL_INIT)
};
#else
#include "trace/kernels/kernel_decls.h"

const lanes_wide_kernels LANES_KFN(lanes_wide_kernels) = {.width = 0};
#endif

#endif
