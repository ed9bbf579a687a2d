/* The slab test of rays against one box, shared by the box kernels and the
 * packet traversal of one kernel set (see box_kernels.c for its edge
 * cases). Included only by per-ISA files; static inline. */
#ifndef LANES_TRACE_BOX_CORE_H
#define LANES_TRACE_BOX_CORE_H

#include "trace/kernels/kernel_common.h"

/* The entry and exit of rays against one box, SIMD across rays. */
LANES_BODY vmask box_vs_rays(const lanes_vray *r, const lanes_box *b, vfloat *entry, float exit_scale)
{
    vfloat t1, t2, tin = r->tnear, tout = r->tfar;
    vmask neg;
    /* An empty box (min > max on an axis) is missed. The octant choice of
     * near and far planes already misses boxes inverted by more than the
     * rounding of (plane - o); this catches the rest, once per box. */
    if (!(b->min[0] <= b->max[0] && b->min[1] <= b->max[1] && b->min[2] <= b->max[2])) {
        *entry = tin;
        return vm_false();
    }

    t1 = vf_mul(vf_sub(vf_set1(b->min[0]), r->ox), r->rdx);
    t2 = vf_mul(vf_sub(vf_set1(b->max[0]), r->ox), r->rdx);
    neg = vf_lt(r->rdx, vf_zero());
    tin = vf_max(vf_select(neg, t2, t1), tin);
    tout = vf_min(vf_select(neg, t1, t2), tout);

    t1 = vf_mul(vf_sub(vf_set1(b->min[1]), r->oy), r->rdy);
    t2 = vf_mul(vf_sub(vf_set1(b->max[1]), r->oy), r->rdy);
    neg = vf_lt(r->rdy, vf_zero());
    tin = vf_max(vf_select(neg, t2, t1), tin);
    tout = vf_min(vf_select(neg, t1, t2), tout);

    t1 = vf_mul(vf_sub(vf_set1(b->min[2]), r->oz), r->rdz);
    t2 = vf_mul(vf_sub(vf_set1(b->max[2]), r->oz), r->rdz);
    neg = vf_lt(r->rdz, vf_zero());
    tin = vf_max(vf_select(neg, t2, t1), tin);
    tout = vf_min(vf_select(neg, t1, t2), tout);

    *entry = tin;
    /* 1, or LANES_ROBUST_SCALE in robust traversal */
    tout = vf_mul(tout, vf_set1(exit_scale));
    return vm_and(vf_le(tin, tout), r->live);
}

#endif
