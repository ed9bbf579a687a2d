/* Ray/box slab tests, written once and compiled per instruction set.
 *
 * The slab test (Kay and Kajiya; Williams et al. 2005) with two details that
 * keep it correct at the edges:
 * - near and far planes are chosen by the sign of 1/d, not by min/max of the
 *   two slab distances: a box with min > max then stays empty instead of
 *   being turned inside out.
 * - when d = ±0 and the origin lies exactly on a slab plane, (plane - o) * 1/d
 *   is 0 * inf = NaN. min/max return their second operand on NaN, and the
 *   running interval is always passed second, so a NaN slab distance leaves
 *   the interval as it was: a ray in the plane of a face counts as inside
 *   (boxes are closed). */
#include "trace/kernels/box_core.h"
#include "trace/kernels/kernel_decls.h"

LANES_BODY size_t box_packet_body(const lanes_rays *rays, const uint32_t *idx, size_t n,
                                  const lanes_box *box, uint32_t *hit, float *tentry,
                                  lanes_lane_stats *stats)
{
    size_t hits = 0;
    for (size_t i = 0; i < n; i += LANES_W) {
        lanes_vray r = lanes_load_rays(rays, idx, i, n, false, true);
        vfloat entry;
        vmask m = box_vs_rays(&r, box, &entry, 1.0f);
        LANES_COUNT(stats, r.live);
        lanes_put_bits(hit, i, m);
        if (tentry) lanes_store_hits(tentry, i, n, m, entry);
        hits += (size_t)vm_popcount(m);
    }
    return hits;
}

LANES_BODY size_t box_partition_body(const lanes_rays *rays, const uint32_t *idx, size_t n,
                                     const lanes_box *box, uint32_t *out,
                                     lanes_lane_stats *stats)
{
    size_t kept = 0;
    for (size_t i = 0; i < n; i += LANES_W) {
        lanes_vray r = lanes_load_rays(rays, idx, i, n, false, true);
        vfloat entry;
        vmask m = box_vs_rays(&r, box, &entry, 1.0f);
        LANES_COUNT(stats, r.live);
        vint id;
        if (idx && n - i >= LANES_W) {
            id = vi_loadu((const int32_t *)(const void *)(idx + i));
        } else {
            int32_t ids[LANES_W];
            for (size_t j = 0; j < LANES_W; j++)
                ids[j] = i + j < n ? (int32_t)(idx ? idx[i + j] : i + j) : 0;
            id = vi_loadu(ids);
        }
        /* out may be idx: the writes stay at or below position i, and this
         * iteration's indices are already in registers. */
        kept += (size_t)vi_compress_store((int32_t *)(void *)(out + kept), m, id);
    }
    return kept;
}

/* One ray against N boxes, SIMD across boxes: the wide-BVH node test. The
 * near plane of each axis is the same for all boxes, picked once per ray. */
LANES_BODY size_t box_wide_body(const lanes_ray *ray, const lanes_boxes *boxes, size_t n,
                                uint32_t *hit, float *tentry, lanes_lane_stats *stats)
{
    const float *near_x = ray->rd[0] < 0.0f ? boxes->maxx : boxes->minx;
    const float *far_x = ray->rd[0] < 0.0f ? boxes->minx : boxes->maxx;
    const float *near_y = ray->rd[1] < 0.0f ? boxes->maxy : boxes->miny;
    const float *far_y = ray->rd[1] < 0.0f ? boxes->miny : boxes->maxy;
    const float *near_z = ray->rd[2] < 0.0f ? boxes->maxz : boxes->minz;
    const float *far_z = ray->rd[2] < 0.0f ? boxes->minz : boxes->maxz;
    const vfloat ox = vf_set1(ray->o[0]), oy = vf_set1(ray->o[1]), oz = vf_set1(ray->o[2]);
    const vfloat rx = vf_set1(ray->rd[0]), ry = vf_set1(ray->rd[1]), rz = vf_set1(ray->rd[2]);
    const vfloat tnear = vf_set1(ray->tnear), tfar = vf_set1(ray->tfar);
    size_t hits = 0;

    for (size_t i = 0; i < n; i += LANES_W) {
        vmask live = vm_first_n(n - i);
        vfloat tin = tnear, tout = tfar;
        tin = vf_max(vf_mul(vf_sub(vf_load(near_x + i), ox), rx), tin);
        tout = vf_min(vf_mul(vf_sub(vf_load(far_x + i), ox), rx), tout);
        tin = vf_max(vf_mul(vf_sub(vf_load(near_y + i), oy), ry), tin);
        tout = vf_min(vf_mul(vf_sub(vf_load(far_y + i), oy), ry), tout);
        tin = vf_max(vf_mul(vf_sub(vf_load(near_z + i), oz), rz), tin);
        tout = vf_min(vf_mul(vf_sub(vf_load(far_z + i), oz), rz), tout);
        /* empty boxes (min > max) are missed, however thin: see box_core.h */
        vmask nonempty = vm_and(vf_le(vf_load(boxes->minx + i), vf_load(boxes->maxx + i)),
                                vm_and(vf_le(vf_load(boxes->miny + i), vf_load(boxes->maxy + i)),
                                       vf_le(vf_load(boxes->minz + i), vf_load(boxes->maxz + i))));
        vmask m = vm_and(vm_and(vf_le(tin, tout), live), nonempty);
        LANES_COUNT(stats, live);
        lanes_put_bits(hit, i, m);
        if (tentry) lanes_store_hits(tentry, i, n, m, tin);
        hits += (size_t)vm_popcount(m);
    }
    return hits;
}

/* The entry points: each body instantiated with and without counting. */
LANES_KERNELS_BOX(LANES_KERNEL_ENTRY)
