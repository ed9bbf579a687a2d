/* The suffixed entry points of one kernel set, as the per-ISA files define
 * them and kernel_table.c collects them. Included only by per-ISA files. */
#ifndef LANES_TRACE_KERNEL_DECLS_H
#define LANES_TRACE_KERNEL_DECLS_H

#include "simd/simd.h"
#include "trace/kernels.h"

void LANES_FN(lanes_rays_prepare)(lanes_rays *rays, lanes_rcp_mode mode);

size_t LANES_FN(lanes_box_packet)(const lanes_rays *rays, const uint32_t *idx, size_t n,
                                  const lanes_box *box, uint32_t *hit, float *tentry,
                                  lanes_lane_stats *stats);
size_t LANES_FN(lanes_box_partition)(const lanes_rays *rays, const uint32_t *idx, size_t n,
                                     const lanes_box *box, uint32_t *out,
                                     lanes_lane_stats *stats);
size_t LANES_FN(lanes_box_wide)(const lanes_ray *ray, const lanes_boxes *boxes, size_t n,
                                uint32_t *hit, float *tentry, lanes_lane_stats *stats);

#define LANES_DECLARE_TRI(algo)                                                            \
    size_t LANES_FN(lanes_tri_packet_##algo)(const lanes_rays *rays, const uint32_t *idx,   \
                                             size_t n, const lanes_triangle *tri,          \
                                             uint32_t *hit, lanes_tri_hits *out,           \
                                             lanes_lane_stats *stats);                     \
    size_t LANES_FN(lanes_tri_packet_any_##algo)(const lanes_rays *rays, const uint32_t *idx, \
                                                 size_t n, const lanes_triangle *tri,      \
                                                 uint32_t *hit, lanes_lane_stats *stats);  \
    size_t LANES_FN(lanes_tri_wide_##algo)(const lanes_ray *ray, const lanes_triangles *tris, \
                                           size_t n, uint32_t *hit, lanes_tri_hits *out,   \
                                           lanes_lane_stats *stats);                       \
    long LANES_FN(lanes_tri_wide_closest_##algo)(const lanes_ray *ray,                     \
                                                 const lanes_triangles *tris, size_t n,    \
                                                 float *t, float *u, float *v,             \
                                                 lanes_lane_stats *stats);                 \
    bool LANES_FN(lanes_tri_wide_any_##algo)(const lanes_ray *ray, const lanes_triangles *tris, \
                                             size_t n, lanes_lane_stats *stats);
LANES_DECLARE_TRI(moller)
LANES_DECLARE_TRI(watertight)
#undef LANES_DECLARE_TRI

void LANES_FN(lanes_frustum_build)(const lanes_rays *rays, const uint32_t *idx, size_t n,
                                   lanes_frustum *f);
size_t LANES_FN(lanes_frustum_boxes)(const lanes_frustum *f, const lanes_boxes *boxes, size_t n,
                                     lanes_cull_method method, uint32_t *keep,
                                     lanes_lane_stats *stats);
size_t LANES_FN(lanes_frustum_tris)(const lanes_frustum *f, const lanes_triangles *tris, size_t n,
                                    lanes_cull_method method, uint32_t *keep,
                                    lanes_lane_stats *stats);

struct lanes_bvh2;
struct lanes_wbvh;
void LANES_FN(lanes_trace_wide)(const struct lanes_wbvh *w, const struct lanes_bvh2 *b,
                                lanes_accuracy accuracy, const lanes_ray *rays, size_t n,
                                lanes_hit *hits, lanes_trace_stats *stats);
void LANES_FN(lanes_occluded_wide)(const struct lanes_wbvh *w, const struct lanes_bvh2 *b,
                                   lanes_accuracy accuracy, const lanes_ray *rays, size_t n,
                                   uint8_t *occluded, lanes_trace_stats *stats);
void LANES_FN(lanes_trace_bvh2)(const struct lanes_bvh2 *b, lanes_accuracy accuracy,
                                const lanes_ray *rays, size_t n, lanes_hit *hits,
                                lanes_trace_stats *stats);
void LANES_FN(lanes_occluded_bvh2)(const struct lanes_bvh2 *b, lanes_accuracy accuracy,
                                   const lanes_ray *rays, size_t n, uint8_t *occluded,
                                   lanes_trace_stats *stats);
void LANES_FN(lanes_trace_packet)(const struct lanes_bvh2 *b, const lanes_packet_options *opt,
                                  lanes_rays *rays, uint32_t *prim, float *u, float *v,
                                  uint8_t *occluded, lanes_packet_stats *stats);

#endif
