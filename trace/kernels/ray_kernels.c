/* Ray set-up, SIMD across rays: reciprocal directions, and invalid rays
 * made inactive so that no kernel can report them as hits. */
#include "trace/kernels/kernel_common.h"
#include "trace/kernels/kernel_decls.h"

#include <float.h>

/* x * 0 == 0 holds exactly for finite x: NaN and ±inf give NaN. */
LANES_BODY vmask finite(vfloat x) { return vf_eq(vf_mul(x, vf_zero()), vf_zero()); }

/* lanes_ray_valid on W rays: finite o and d, d != 0, no NaN end. */
LANES_BODY vmask rays_valid(vfloat ox, vfloat oy, vfloat oz, vfloat dx, vfloat dy, vfloat dz, vfloat tnear, vfloat tfar)
{
    const vfloat zero = vf_zero();
    vmask ok = vm_and(finite(ox), vm_and(finite(oy), finite(oz)));
    ok = vm_and(ok, vm_and(finite(dx), vm_and(finite(dy), finite(dz))));
    ok = vm_and(ok, vm_not(vm_or(vf_isnan(tnear), vf_isnan(tfar))));
    return vm_and(ok, vm_or(vf_neq(dx, zero), vm_or(vf_neq(dy, zero), vf_neq(dz, zero))));
}

/* Infinite ends become ±FLT_MAX: a slab that a d = ±0 ray never enters has
 * both distances at the same infinity, and only finite ends keep such an
 * empty interval from overlapping [tnear, tfar]. An invalid ray gets the
 * empty interval [inf, -inf]. */
LANES_BODY void rays_interval(vmask ok, vfloat *tnear, vfloat *tfar)
{
    *tnear = vf_select(ok, vf_max(*tnear, vf_set1(-FLT_MAX)), vf_set1(INFINITY));
    *tfar = vf_select(ok, vf_min(*tfar, vf_set1(FLT_MAX)), vf_set1(-INFINITY));
}

void LANES_FN(lanes_rays_prepare)(lanes_rays *r, lanes_rcp_mode mode)
{
    for (size_t i = 0; i < r->count; i += LANES_W) {
        vfloat dx = vf_load(r->dx + i), dy = vf_load(r->dy + i), dz = vf_load(r->dz + i);
        vfloat tn = vf_load(r->tnear + i), tf = vf_load(r->tfar + i);
        vmask ok = rays_valid(vf_load(r->ox + i), vf_load(r->oy + i), vf_load(r->oz + i), dx, dy, dz, tn, tf);
        vfloat rdx, rdy, rdz;
        if (mode == LANES_RCP_FAST) {
            /* The estimate is inf for ±0 and for denormals, and the Newton
             * step turns inf into NaN (0 * inf): tiny components take the
             * exact reciprocal (±inf for ±0), which the slab test handles. */
            const vfloat tiny = vf_set1(0x1p-60f);
            rdx = vf_select(vf_lt(vf_abs(dx), tiny), vf_rcp(dx), vf_rcp_nr(dx));
            rdy = vf_select(vf_lt(vf_abs(dy), tiny), vf_rcp(dy), vf_rcp_nr(dy));
            rdz = vf_select(vf_lt(vf_abs(dz), tiny), vf_rcp(dz), vf_rcp_nr(dz));
        } else {
            rdx = vf_rcp(dx), rdy = vf_rcp(dy), rdz = vf_rcp(dz);
        }
        rays_interval(ok, &tn, &tf);
        lanes_store_below(r->rdx, i, r->count, rdx);
        lanes_store_below(r->rdy, i, r->count, rdy);
        lanes_store_below(r->rdz, i, r->count, rdz);
        lanes_store_below(r->tnear, i, r->count, tn);
        lanes_store_below(r->tfar, i, r->count, tf);
    }
}

size_t LANES_FN(lanes_rays_load_soa)(const float *const *soa, size_t n, const float *box, float far2, lanes_ray *out,
                                     uint8_t *flags)
{
    const vfloat zero = vf_zero();
    size_t flagged = 0;
    for (size_t i = 0; i < n; i += LANES_W) {
        size_t here = n - i < LANES_W ? n - i : LANES_W;
        vmask in = vm_first_n(here);
        vfloat v[8];
        for (int k = 0; k < 8; k++) v[k] = here == LANES_W ? vf_loadu(soa[k] + i) : vf_load_masked(in, soa[k] + i);
        vmask ok = rays_valid(v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7]);
        vfloat tn = v[6], tf = v[7];
        rays_interval(ok, &tn, &tf);
        vmask far = vm_false();
        if (box) {
            /* each step rounds by at most 2^-24 relative, so a square
             * within 2^-18 of far2 is flagged for the exact test */
            vfloat r2 = zero;
            for (int k = 0; k < 3; k++) {
                vfloat e = vf_sub(vf_max(vf_set1(box[3 + k]), v[k]), vf_min(vf_set1(box[k]), v[k]));
                r2 = vf_add(r2, vf_mul(e, e));
            }
            far = vm_and(ok, vf_gt(r2, vf_set1(far2 * (1.0f - 0x1p-18f))));
        }
        float lane[11][LANES_W];
        for (int k = 0; k < 6; k++) vf_storeu(lane[k], v[k]);
        vf_storeu(lane[6], vf_rcp(v[3]));
        vf_storeu(lane[7], vf_rcp(v[4]));
        vf_storeu(lane[8], vf_rcp(v[5]));
        vf_storeu(lane[9], tn);
        vf_storeu(lane[10], tf);
        uint32_t bad = vm_bits(vm_andnot(in, ok)), maybe_far = vm_bits(far);
        for (size_t j = 0; j < here; j++) {
            lanes_ray *r = &out[i + j];
            for (int k = 0; k < 3; k++) r->o[k] = lane[k][j], r->d[k] = lane[3 + k][j], r->rd[k] = lane[6 + k][j];
            r->tnear = lane[9][j], r->tfar = lane[10][j];
            uint8_t f = (bad >> j & 1u) ? LANES_RAY_INVALID : (maybe_far >> j & 1u) ? LANES_RAY_MAYBE_FAR : 0;
            flags[i + j] = f;
            flagged += f != 0;
        }
    }
    return flagged;
}
