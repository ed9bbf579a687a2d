/* Every kernel of a kernel set, declared once. From these rows come the
 * lanes_kernels table's members (kernels.h), each set's prototypes and table
 * (trace/kernels/kernel_decls.h, kernel_table.c) and the counting and
 * non-counting entry points (trace/kernels/kernel_decls.h). Adding a kernel:
 * its body in its family's file, one row here, its test.
 *
 *   X(kind, ret, name, params, args)
 *
 *   PLAIN         the family's file defines LANES_FN(lanes_<name>) itself
 *   COUNTED       the file defines `LANES_BODY ret <name>_body(params)`, whose
 *                 last parameter is the stats pointer; the entry point
 *                 instantiates it twice, with stats and with NULL, so that the
 *                 second copy carries no counting code (args: the parameters
 *                 before stats, to forward)
 *   COUNTED_VOID  the same, for a body returning void
 *   PER_ALGO      one entry point per ray/triangle algorithm (a table member
 *                 indexed by lanes_tri_algo: _moller, _watertight), each the
 *                 COUNTED instantiation of `<name>_body(algo, params)`
 *
 * One list per family, each expanded by its family's file; LANES_KERNELS is
 * all of them. Conventions every kernel keeps: kernels.h. */
#ifndef LANES_TRACE_KERNEL_LIST_H
#define LANES_TRACE_KERNEL_LIST_H

/* ray_kernels.c: computes 1/d and deactivates invalid rays.
 * rays_load_soa: n rays given as eight arrays (ox, oy, oz, dx, dy, dz,
 *   tnear, tfar; any alignment) into out[0..n-1] prepared as
 *   lanes_ray_prepare_rcp prepares one in the exact mode (1/d exact,
 *   infinite ends made finite, an invalid ray inactive). flags[i]:
 *   LANES_RAY_INVALID for a ray lanes_ray_valid refuses; else
 *   LANES_RAY_MAYBE_FAR when box (min xyz, max xyz; may be NULL) and the
 *   origin span a diagonal whose square may exceed far2 (a float bound
 *   that never misses one beyond: the caller decides in double). Returns
 *   the number of rays flagged. */
#define LANES_KERNELS_RAY(X)                                                               \
    X(PLAIN, void, rays_prepare, (lanes_rays * rays, lanes_rcp_mode mode), ())             \
    X(PLAIN, size_t, rays_load_soa,                                                        \
      (const float *const *soa, size_t n, const float *box, float far2, lanes_ray *out,    \
       uint8_t *flags),                                                                    \
      ())

/* box_kernels.c
 * box_packet: N rays against one box. idx, when not NULL, names the rays to
 *   test (idx[0..n-1]) and bit i of hit is the ray idx[i]; otherwise rays
 *   0..n-1. tentry (may be NULL) receives max(tnear, entry distance) for
 *   hits. Returns the number of hits.
 * box_partition: the partition step of partition traversal: writes to out
 *   the entries of idx[0..n-1] whose rays hit the box, in order, and returns
 *   their number (out may equal idx).
 * box_wide: one ray against N boxes (a wide node's children). */
#define LANES_KERNELS_BOX(X)                                                               \
    X(COUNTED, size_t, box_packet,                                                         \
      (const lanes_rays *rays, const uint32_t *idx, size_t n, const lanes_box *box,        \
       uint32_t *hit, float *tentry, lanes_lane_stats *stats),                             \
      (rays, idx, n, box, hit, tentry))                                                    \
    X(COUNTED, size_t, box_partition,                                                      \
      (const lanes_rays *rays, const uint32_t *idx, size_t n, const lanes_box *box,        \
       uint32_t *out, lanes_lane_stats *stats),                                            \
      (rays, idx, n, box, out))                                                            \
    X(COUNTED, size_t, box_wide,                                                           \
      (const lanes_ray *ray, const lanes_boxes *boxes, size_t n, uint32_t *hit,            \
       float *tentry, lanes_lane_stats *stats),                                            \
      (ray, boxes, n, hit, tentry))

/* triangle_kernels.c, per algorithm
 * tri_packet: N rays against one triangle: per-ray t, u, v for hits only.
 * tri_packet_any: the same for occlusion: hit bits, no t/u/v.
 * tri_wide: one ray against N triangles: per-triangle results, hits only.
 * tri_wide_closest: one ray against N triangles, closest hit: the index of
 *   the nearest hit (ties: the lowest index) or -1, and its t, u, v.
 * tri_wide_any: one ray against N triangles, occlusion: stops at the first
 *   vector holding a hit. */
#define LANES_KERNELS_TRI(X)                                                               \
    X(PER_ALGO, size_t, tri_packet,                                                        \
      (const lanes_rays *rays, const uint32_t *idx, size_t n, const lanes_triangle *tri,   \
       uint32_t *hit, lanes_tri_hits *out, lanes_lane_stats *stats),                       \
      (rays, idx, n, tri, hit, out))                                                       \
    X(PER_ALGO, size_t, tri_packet_any,                                                    \
      (const lanes_rays *rays, const uint32_t *idx, size_t n, const lanes_triangle *tri,   \
       uint32_t *hit, lanes_lane_stats *stats),                                            \
      (rays, idx, n, tri, hit))                                                            \
    X(PER_ALGO, size_t, tri_wide,                                                          \
      (const lanes_ray *ray, const lanes_triangles *tris, size_t n, uint32_t *hit,         \
       lanes_tri_hits *out, lanes_lane_stats *stats),                                      \
      (ray, tris, n, hit, out))                                                            \
    X(PER_ALGO, long, tri_wide_closest,                                                    \
      (const lanes_ray *ray, const lanes_triangles *tris, size_t n, float *t, float *u,    \
       float *v, lanes_lane_stats *stats),                                                 \
      (ray, tris, n, t, u, v))                                                             \
    X(PER_ALGO, bool, tri_wide_any,                                                        \
      (const lanes_ray *ray, const lanes_triangles *tris, size_t n, lanes_lane_stats *stats), \
      (ray, tris, n))

/* frustum_kernels.c
 * frustum_build: the frustum of rays idx[0..n-1] (all of 0..n-1 when idx is
 *   NULL), SIMD across the rays.
 * frustum_boxes, frustum_tris: culling, SIMD across primitives: bit i set =
 *   primitive i may be hit by some ray of the frustum; clear = no ray can
 *   hit it. Return the number of bits set. */
#define LANES_KERNELS_FRUSTUM(X)                                                           \
    X(PLAIN, void, frustum_build,                                                          \
      (const lanes_rays *rays, const uint32_t *idx, size_t n, lanes_frustum *f), ())       \
    X(COUNTED, size_t, frustum_boxes,                                                      \
      (const lanes_frustum *f, const lanes_boxes *boxes, size_t n, lanes_cull_method method, \
       uint32_t *keep, lanes_lane_stats *stats),                                           \
      (f, boxes, n, method, keep))                                                         \
    X(COUNTED, size_t, frustum_tris,                                                       \
      (const lanes_frustum *f, const lanes_triangles *tris, size_t n,                      \
       lanes_cull_method method, uint32_t *keep, lanes_lane_stats *stats),                 \
      (f, tris, n, method, keep))

/* traverse_kernels.c: single-ray traversal of n prepared rays
 * (lanes_ray_prepare_rcp), one after the other. The wide form reads only a
 * wide BVH of the table's wide_width children (SIMD across a node's children
 * and across a leaf block's triangles); the BVH2 form visits two children at a time,
 * as the thesis' "single" baseline, and tests leaf triangles with the wide
 * triangle kernel. */
#define LANES_KERNELS_TRAVERSE(X) LANES_KERNELS_TRAVERSE_WIDE(X) LANES_KERNELS_TRAVERSE_BVH2(X)
#define LANES_KERNELS_TRAVERSE_WIDE(X)                                                     \
    X(COUNTED_VOID, void, trace_wide,                                                      \
      (const struct lanes_wbvh *w, lanes_accuracy accuracy, const lanes_ray *rays,         \
       size_t n, lanes_hit *hits, lanes_trace_stats *stats),                               \
      (w, accuracy, rays, n, hits))                                                        \
    X(COUNTED_VOID, void, occluded_wide,                                                   \
      (const struct lanes_wbvh *w, lanes_accuracy accuracy, const lanes_ray *rays,         \
       size_t n, uint8_t *occluded, lanes_trace_stats *stats),                             \
      (w, accuracy, rays, n, occluded))
#define LANES_KERNELS_TRAVERSE_BVH2(X)                                                     \
    X(COUNTED_VOID, void, trace_bvh2,                                                      \
      (const struct lanes_bvh2 *b, lanes_accuracy accuracy, const lanes_ray *rays,         \
       size_t n, lanes_hit *hits, lanes_trace_stats *stats),                               \
      (b, accuracy, rays, n, hits))                                                        \
    X(COUNTED_VOID, void, occluded_bvh2,                                                   \
      (const struct lanes_bvh2 *b, lanes_accuracy accuracy, const lanes_ray *rays,         \
       size_t n, uint8_t *occluded, lanes_trace_stats *stats),                             \
      (b, accuracy, rays, n, occluded))

/* hybrid_kernels.c: n prepared rays as packets of LANES_W consecutive rays
 * through the same wide BVH as trace_wide, SIMD across a packet's rays at
 * each node until one of them is left, which goes on alone (hybrid
 * traversal). Same hits as trace_wide, except where the visiting order
 * decides (ties between leaves, hits on a box's rounding boundary). */
#define LANES_KERNELS_HYBRID(X)                                                            \
    X(COUNTED_VOID, void, trace_hybrid,                                                    \
      (const struct lanes_wbvh *w, lanes_accuracy accuracy, const lanes_ray *rays,         \
       size_t n, lanes_hit *hits, lanes_trace_stats *stats),                               \
      (w, accuracy, rays, n, hits))                                                        \
    X(COUNTED_VOID, void, occluded_hybrid,                                                 \
      (const struct lanes_wbvh *w, lanes_accuracy accuracy, const lanes_ray *rays,         \
       size_t n, uint8_t *occluded, lanes_trace_stats *stats),                             \
      (w, accuracy, rays, n, occluded))

/* stream_kernels.c: n prepared rays as a stream: sorted into direction
 * octants as they come, each group of up to 32 rays of one octant walks the
 * wide BVH together (a node's planes loaded once per group, each ray tested
 * against all children), as Embree's rtcIntersect1M / rtcOccluded1M.
 * Occlusion: occluded_wide's answers, bit for bit. Closest hit: trace_wide's
 * but where the visiting order decides, as for trace_hybrid. */
#define LANES_KERNELS_STREAM(X)                                                            \
    X(COUNTED_VOID, void, trace_stream,                                                    \
      (const struct lanes_wbvh *w, lanes_accuracy accuracy, const lanes_ray *rays,         \
       size_t n, lanes_hit *hits, lanes_trace_stats *stats),                               \
      (w, accuracy, rays, n, hits))                                                        \
    X(COUNTED_VOID, void, occluded_stream,                                                 \
      (const struct lanes_wbvh *w, lanes_accuracy accuracy, const lanes_ray *rays,         \
       size_t n, uint8_t *occluded, lanes_trace_stats *stats),                             \
      (w, accuracy, rays, n, occluded))

/* packet_kernels.c: one packet of rays->count (<= LANES_PACKET_MAX_RAYS)
 * prepared rays through the BVH2. Closest hit: each ray's tfar shrinks to
 * its hit distance, and prim[i], u[i], v[i] are written for rays that hit
 * (prim must be LANES_NO_HIT on entry). Occlusion: occluded[i] is set to 1
 * for rays that hit anything (and their tfar to -inf); u, v, prim may be
 * NULL. */
#define LANES_KERNELS_PACKET(X)                                                            \
    X(COUNTED_VOID, void, trace_packet,                                                    \
      (const struct lanes_bvh2 *b, const lanes_packet_options *opt, lanes_rays *rays,      \
       uint32_t *prim, float *u, float *v, uint8_t *occluded, lanes_packet_stats *stats),  \
      (b, opt, rays, prim, u, v, occluded))

/* shade_kernels.c: the shaders' building blocks on n items in SoA form
 * (component k of item i at p[k * n + i]), any n; parameters uniform over
 * the call (one material) but the albedo: NULL takes the material's, else
 * each item's (3, SoA; a texture's). See trace/bsdf.h and trace/texture.h.
 * bsdf_eval: f (3 channels) and the sampling pdf for directions wo, wi.
 * bsdf_sample: a direction wi for each wo from u (3 numbers in [0, 1) per
 *   item), its weight f cos / pdf (3), pdf, and flags (LANES_BSDF_VALID,
 *   LANES_BSDF_DELTA).
 * texture_color: the texture's blend weight and color (3) at points p.
 * noise: gradient noise in [-1, 1] at points p. */
#define LANES_KERNELS_SHADE(X)                                                             \
    X(PLAIN, void, bsdf_eval,                                                              \
      (const lanes_bsdf *b, size_t n, const float *albedo, const float *wo, const float *wi, \
       float *f, float *pdf),                                                              \
      ())                                                                                  \
    X(PLAIN, void, bsdf_sample,                                                            \
      (const lanes_bsdf *b, size_t n, const float *albedo, const float *wo, const float *u, \
       float *wi, float *weight, float *pdf, uint8_t *flags),                              \
      ())                                                                                  \
    X(PLAIN, void, texture_color,                                                          \
      (const lanes_texture *t, size_t n, const float *p, float *weight, float *color), ())  \
    X(PLAIN, void, noise, (size_t n, const float *p, float *out), ())

#define LANES_KERNELS(X)                                                                   \
    LANES_KERNELS_RAY(X)                                                                   \
    LANES_KERNELS_BOX(X)                                                                   \
    LANES_KERNELS_TRI(X)                                                                   \
    LANES_KERNELS_FRUSTUM(X)                                                               \
    LANES_KERNELS_TRAVERSE(X)                                                              \
    LANES_KERNELS_HYBRID(X)                                                                \
    LANES_KERNELS_STREAM(X)                                                                \
    LANES_KERNELS_PACKET(X)                                                                \
    LANES_KERNELS_SHADE(X)

/* The kernels that read a wide BVH: compiled for the set's own node width
 * (wide_width) and again for each wider one (trace/kernels/wide_variant.h). */
#define LANES_KERNELS_WIDE_BVH(X)                                                          \
    LANES_KERNELS_TRAVERSE_WIDE(X)                                                         \
    LANES_KERNELS_HYBRID(X)                                                                \
    LANES_KERNELS_STREAM(X)

/* The lanes_kernels member of a row. */
#define LANES_KERNEL_MEMBER(kind, ret, name, params, args) LANES_KERNEL_MEMBER_##kind(ret, name, params)
#define LANES_KERNEL_MEMBER_PLAIN(ret, name, params) ret(*name) params;
#define LANES_KERNEL_MEMBER_COUNTED(ret, name, params) ret(*name) params;
#define LANES_KERNEL_MEMBER_COUNTED_VOID(ret, name, params) ret(*name) params;
#define LANES_KERNEL_MEMBER_PER_ALGO(ret, name, params) ret(*name[LANES_TRI_ALGO_COUNT]) params;

#endif
