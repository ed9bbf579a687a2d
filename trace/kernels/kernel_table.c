/* The kernel table of one instruction set: the only object of a per-ISA
 * library that other code reaches, through lanes_kernels_for(). */
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
