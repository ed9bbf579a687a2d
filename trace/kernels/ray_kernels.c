/* Ray set-up, SIMD across rays: reciprocal directions, and invalid rays
 * made inactive so that no kernel can report them as hits. */
#include "trace/kernels/kernel_common.h"
#include "trace/kernels/kernel_decls.h"

#include <float.h>

/* x * 0 == 0 holds exactly for finite x: NaN and ±inf give NaN. */
LANES_BODY vmask finite(vfloat x) { return vf_eq(vf_mul(x, vf_zero()), vf_zero()); }

void LANES_FN(lanes_rays_prepare)(lanes_rays *r, lanes_rcp_mode mode)
{
    const vfloat zero = vf_zero();
    for (size_t i = 0; i < r->count; i += LANES_W) {
        vfloat dx = vf_load(r->dx + i), dy = vf_load(r->dy + i), dz = vf_load(r->dz + i);
        vfloat tnear = vf_load(r->tnear + i), tfar = vf_load(r->tfar + i);
        vmask ok = vm_and(finite(vf_load(r->ox + i)),
                          vm_and(finite(vf_load(r->oy + i)), finite(vf_load(r->oz + i))));
        ok = vm_and(ok, vm_and(finite(dx), vm_and(finite(dy), finite(dz))));
        ok = vm_and(ok, vm_not(vm_or(vf_isnan(tnear), vf_isnan(tfar))));
        ok = vm_and(ok, vm_or(vf_neq(dx, zero), vm_or(vf_neq(dy, zero), vf_neq(dz, zero))));
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
        /* Infinite ends become ±FLT_MAX: a slab that a d = ±0 ray never
         * enters has both distances at the same infinity, and only finite
         * ends keep such an empty interval from overlapping [tnear, tfar]. */
        vfloat tn = vf_select(ok, vf_max(tnear, vf_set1(-FLT_MAX)), vf_set1(INFINITY));
        vfloat tf = vf_select(ok, vf_min(tfar, vf_set1(FLT_MAX)), vf_set1(-INFINITY));
        lanes_store_below(r->rdx, i, r->count, rdx);
        lanes_store_below(r->rdy, i, r->count, rdy);
        lanes_store_below(r->rdz, i, r->count, rdz);
        lanes_store_below(r->tnear, i, r->count, tn);
        lanes_store_below(r->tfar, i, r->count, tf);
    }
}
