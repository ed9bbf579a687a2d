/* Ray/triangle tests, written once and compiled per instruction set, each in
 * two forms: N rays against one triangle (packets) and one ray against N
 * triangles (wide leaves). Both forms share one vector core per algorithm
 * (triangle_core.h); the form only decides which operand is broadcast. */
#include "trace/kernels/kernel_decls.h"
#include "trace/kernels/triangle_core.h"

LANES_BODY size_t tri_packet_body(lanes_tri_algo algo, const lanes_rays *rays, const uint32_t *idx,
                                  size_t n, const lanes_triangle *tri, uint32_t *hit,
                                  lanes_tri_hits *out, lanes_lane_stats *stats)
{
    size_t hits = 0;
    for (size_t i = 0; i < n; i += LANES_W) {
        lanes_vray r = lanes_load_rays(rays, idx, i, n, true, false);
        tri_result h = tri_vs_rays(algo, &r, tri, out != NULL);
        LANES_COUNT(stats, r.live);
        lanes_put_bits(hit, i, h.hit);
        if (out) {
            lanes_store_hits(out->t, i, n, h.hit, h.t);
            lanes_store_hits(out->u, i, n, h.hit, h.u);
            lanes_store_hits(out->v, i, n, h.hit, h.v);
        }
        hits += (size_t)vm_popcount(h.hit);
    }
    return hits;
}

LANES_BODY size_t tri_wide_body(lanes_tri_algo algo, const lanes_ray *ray,
                                const lanes_triangles *tris, size_t n, uint32_t *hit,
                                lanes_tri_hits *out, lanes_lane_stats *stats)
{
    wide_setup w;
    wide_setup_init(&w, algo, ray, tris);
    size_t hits = 0;
    for (size_t i = 0; i < n; i += LANES_W) {
        vmask live = vm_first_n(n - i);
        tri_result h = ray_vs_tris(algo, &w, i, w.tfar, live, out != NULL);
        LANES_COUNT(stats, live);
        lanes_put_bits(hit, i, h.hit);
        if (out) {
            lanes_store_hits(out->t, i, n, h.hit, h.t);
            lanes_store_hits(out->u, i, n, h.hit, h.u);
            lanes_store_hits(out->v, i, n, h.hit, h.v);
        }
        hits += (size_t)vm_popcount(h.hit);
    }
    return hits;
}

LANES_BODY size_t tri_packet_any_body(lanes_tri_algo algo, const lanes_rays *rays, const uint32_t *idx,
                                      size_t n, const lanes_triangle *tri, uint32_t *hit,
                                      lanes_lane_stats *stats)
{
    return tri_packet_body(algo, rays, idx, n, tri, hit, NULL, stats);
}

LANES_BODY long tri_wide_closest_body(lanes_tri_algo algo, const lanes_ray *ray, const lanes_triangles *tris,
                                      size_t n, float *t, float *u, float *v, lanes_lane_stats *stats)
{
    return tri_closest_body(algo, ray, tris, n, t, u, v, stats);
}

LANES_BODY bool tri_wide_any_body(lanes_tri_algo algo, const lanes_ray *ray, const lanes_triangles *tris,
                                  size_t n, lanes_lane_stats *stats)
{
    return tri_any_body(algo, ray, tris, n, stats);
}

/* The entry points: one per algorithm and form, each body instantiated with
 * and without counting. */
LANES_KERNELS_TRI(LANES_KERNEL_ENTRY)
