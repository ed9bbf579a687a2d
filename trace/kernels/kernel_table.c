/* The kernel table of one instruction set: the only object of a per-ISA
 * library that other code reaches, through lanes_kernels_for(). */
#include "trace/kernels/kernel_common.h"
#include "trace/kernels/kernel_decls.h"

const lanes_kernels LANES_FN(lanes_kernels) = {
    .isa = LANES_THIS_ISA,
    .lanes = LANES_W,
    .name = LANES_KSET_NAME,
    .compiled_features = LANES_COMPILED_FEATURES,
    .rays_prepare = LANES_FN(lanes_rays_prepare),
    .box_packet = LANES_FN(lanes_box_packet),
    .box_partition = LANES_FN(lanes_box_partition),
    .box_wide = LANES_FN(lanes_box_wide),
    .tri_packet = {LANES_FN(lanes_tri_packet_moller), LANES_FN(lanes_tri_packet_watertight)},
    .tri_packet_any = {LANES_FN(lanes_tri_packet_any_moller),
                       LANES_FN(lanes_tri_packet_any_watertight)},
    .tri_wide = {LANES_FN(lanes_tri_wide_moller), LANES_FN(lanes_tri_wide_watertight)},
    .tri_wide_closest = {LANES_FN(lanes_tri_wide_closest_moller),
                         LANES_FN(lanes_tri_wide_closest_watertight)},
    .tri_wide_any = {LANES_FN(lanes_tri_wide_any_moller), LANES_FN(lanes_tri_wide_any_watertight)},
    .frustum_build = LANES_FN(lanes_frustum_build),
    .frustum_boxes = LANES_FN(lanes_frustum_boxes),
    .frustum_tris = LANES_FN(lanes_frustum_tris),
    .wide_width = LANES_WIDE_WIDTH,
    .trace_wide = LANES_FN(lanes_trace_wide),
    .occluded_wide = LANES_FN(lanes_occluded_wide),
    .trace_bvh2 = LANES_FN(lanes_trace_bvh2),
    .occluded_bvh2 = LANES_FN(lanes_occluded_bvh2),
    .trace_packet = LANES_FN(lanes_trace_packet),
};
