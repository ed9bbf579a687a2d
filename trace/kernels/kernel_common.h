/* Helpers for the per-ISA kernel files (compiled once per set, like them).
 * Everything here is static inline: see simd/simd.h. */
#ifndef LANES_TRACE_KERNEL_COMMON_H
#define LANES_TRACE_KERNEL_COMMON_H

#include "simd/simd.h"
#include "trace/kernels.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

/* Kernel bodies are instantiated twice by their entry points, once with
 * counting and once with stats == NULL, so that the second copy carries no
 * counting code at all. That only works when the body is really inlined. */
#define LANES_BODY static inline __attribute__((always_inline))

/* A rare path (an exact fallback) kept out of line, so that the hot loop
 * that calls it keeps its registers and its code size; static (one copy
 * per kernel set) but not inline, and unused in files that never call it. */
#define LANES_COLD static __attribute__((noinline, cold, unused))

/* Lane accounting for one vector iteration whose real lanes are `live`. */
#define LANES_COUNT(stats, live)                                                           \
    do {                                                                                   \
        if (stats) {                                                                       \
            (stats)->vector_ops++;                                                         \
            (stats)->lane_slots += LANES_W;                                                \
            (stats)->active_lanes += (uint64_t)vm_popcount(live);                          \
        }                                                                                  \
    } while (0)

/* Writes the LANES_W result bits of the iteration starting at element i
 * (i is a multiple of LANES_W, and 32 is a multiple of LANES_W). */
static inline void lanes_put_bits(uint32_t *mask, size_t i, vmask m)
{
    uint32_t bits = vm_bits(m);
    if (i % 32 == 0)
        mask[i / 32] = bits;
    else
        mask[i / 32] |= bits << (i % 32);
}

/* Writes v into the lanes of m of p[i .. i+LANES_W) for an array of n
 * elements the caller gave this call alone (kernels.h: results past n are
 * never written). A whole vector below n is merged (a read, a blend and a
 * write, where a masked store is slow: see simd/vec1_scalar.h); the tail
 * past n takes the masked store, which touches nothing beyond it. Integer
 * results go through vi_as_vf: the store moves bits, not values. */
static inline void lanes_store_hits(float *p, size_t i, size_t n, vmask m, vfloat v)
{
    if (n - i >= LANES_W)
        vf_store_merge(p + i, m, v);
    else
        vf_store_masked(p + i, m, v);
}

/* Writes every lane of v that lies below n to p[i ..]: a plain store for a
 * whole vector, a masked one for the tail. */
static inline void lanes_store_below(float *p, size_t i, size_t n, vfloat v)
{
    if (n - i >= LANES_W)
        vf_storeu(p + i, v);
    else
        vf_store_masked(p + i, vm_first_n(n - i), v);
}

/* Ray data of one vector iteration, by position (idx == NULL) or through an
 * index array. Past n, lanes repeat the first ray of the iteration: it is
 * valid data, and `live` masks the lanes out. */
typedef struct {
    vfloat ox, oy, oz, dx, dy, dz, rdx, rdy, rdz, tnear, tfar;
    vmask live;
} lanes_vray;

LANES_BODY lanes_vray lanes_load_rays(const lanes_rays *r, const uint32_t *idx, size_t i, size_t n,
                                      bool with_dir, bool with_rdir)
{
    lanes_vray v;
    size_t rem = n - i;
    v.live = vm_first_n(rem);
    if (idx) {
        vint id;
        if (rem >= LANES_W) {
            id = vi_loadu((const int32_t *)(const void *)(idx + i));
        } else {
            int32_t tail[LANES_W];
            for (size_t j = 0; j < LANES_W; j++) tail[j] = (int32_t)idx[i + (j < rem ? j : 0)];
            id = vi_loadu(tail);
        }
        v.ox = vf_gather(r->ox, id);
        v.oy = vf_gather(r->oy, id);
        v.oz = vf_gather(r->oz, id);
        v.tnear = vf_gather(r->tnear, id);
        v.tfar = vf_gather(r->tfar, id);
        if (with_dir) {
            v.dx = vf_gather(r->dx, id);
            v.dy = vf_gather(r->dy, id);
            v.dz = vf_gather(r->dz, id);
        }
        if (with_rdir) {
            v.rdx = vf_gather(r->rdx, id);
            v.rdy = vf_gather(r->rdy, id);
            v.rdz = vf_gather(r->rdz, id);
        }
    } else {
        /* SoA arrays are padded to LANES_MAX_W, so full loads stay inside. */
        v.ox = vf_load(r->ox + i);
        v.oy = vf_load(r->oy + i);
        v.oz = vf_load(r->oz + i);
        v.tnear = vf_load(r->tnear + i);
        v.tfar = vf_load(r->tfar + i);
        if (with_dir) {
            v.dx = vf_load(r->dx + i);
            v.dy = vf_load(r->dy + i);
            v.dz = vf_load(r->dz + i);
        }
        if (with_rdir) {
            v.rdx = vf_load(r->rdx + i);
            v.rdy = vf_load(r->rdy + i);
            v.rdz = vf_load(r->rdz + i);
        }
    }
    if (!with_dir) v.dx = v.dy = v.dz = vf_zero();
    if (!with_rdir) v.rdx = v.rdy = v.rdz = vf_zero();
    return v;
}

/* The wide BVH this set's traversal reads: one node test is one vector
 * operation, except for the scalar set, which loops over a 4-wide node.
 * wide_variant.h compiles the wide-BVH kernels again with a wider node
 * (LANES_WIDE_WIDTH defined first), tested in width / LANES_W vectors. */
#ifndef LANES_WIDE_WIDTH
#define LANES_WIDE_WIDTH (LANES_W == 1 ? 4 : LANES_W)
#endif
_Static_assert(LANES_WIDE_WIDTH % LANES_W == 0 && LANES_WIDE_WIDTH <= 16,
               "a node is whole vectors of the set, at most 16 children");

/* Unit roundoff of float, for the outward widening of conservative bounds. */
#define LANES_U 0x1p-24f

#endif
