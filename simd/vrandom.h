/* Random numbers for the shaders as a pure function of a counter: a
 * lane's number depends only on (pixel, sample, depth, dimension), never on
 * the width, the lane or the order in which paths are shaded, so a path's
 * samples are the same whether it is traced alone, in a packet or in a
 * sorted stream, at every set. No state to carry, split or store.
 *
 * The mixing function is Wellons' "lowbias32" (xor-shift, multiply,
 * twice), a bijection on 32 bits with low avalanche bias; the four counters
 * are folded in one after another, each through the whole function.
 * tests/test_simd_math_set.c checks every set against a plain C copy, bit
 * for bit and in permuted lanes, and the uniformity of the floats. Its
 * plain C twin for one value, for baseline code: simd/counter_random.h.
 *
 * Included by per-ISA files; everything is static inline. */
#ifndef LANES_SIMD_VRANDOM_H
#define LANES_SIMD_VRANDOM_H

#include "simd.h"

static inline vint vi_hash32(vint x)
{
    x = vi_xor(x, vi_srl(x, 16));
    x = vi_mul(x, vi_set1((int32_t)0x7feb352du));
    x = vi_xor(x, vi_srl(x, 15));
    x = vi_mul(x, vi_set1((int32_t)0x846ca68bu));
    return vi_xor(x, vi_srl(x, 16));
}

/* 32 random bits for each lane's (pixel, sample, depth, dimension). */
static inline vint vi_random_bits(vint pixel, vint sample, vint depth, vint dimension)
{
    vint h = vi_hash32(pixel);
    h = vi_hash32(vi_add(h, sample));
    h = vi_hash32(vi_add(h, depth));
    return vi_hash32(vi_add(h, dimension));
}

/* A float in [0, 1): the top 24 bits over 2^24, exactly, so 1 - 2^-24 is
 * the largest and every value is a multiple of 2^-24. */
static inline vfloat vf_random(vint pixel, vint sample, vint depth, vint dimension)
{
    vint bits = vi_random_bits(pixel, sample, depth, dimension);
    return vf_mul(vi_to_vf(vi_srl(bits, 8)), vf_set1(0x1p-24f));
}

#endif
