/* The kernel table of one instruction set: with the wider-node tables of
 * wide_variant.h, the only objects of a per-ISA library that other code
 * reaches, through lanes_kernels_for() and lanes_kernels_for_width(). */
#include "trace/kernels/kernel_common.h"
#include "trace/kernels/kernel_decls.h"

const lanes_kernels LANES_FN(lanes_kernels) = {
    .isa = LANES_THIS_ISA,
    .lanes = LANES_W,
    .name = LANES_KSET_NAME,
    .compiled_features = LANES_COMPILED_FEATURES,
    .wide_width = LANES_WIDE_WIDTH,
    LANES_KERNELS(LANES_KERNEL_INIT)
};
