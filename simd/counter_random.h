/* The counter-based random numbers of simd/vrandom.h for one value, in
 * plain C (no intrinsics): for baseline code, which must draw the same
 * numbers as the per-set shaders, and for any other deterministic hashing
 * the tools need. vrandom.h documents the construction. */
#ifndef LANES_SIMD_COUNTER_RANDOM_H
#define LANES_SIMD_COUNTER_RANDOM_H

#include <stdint.h>

/* Wellons' "lowbias32": vi_hash32 for one value. */
static inline uint32_t lanes_hash32(uint32_t x)
{
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

/* The 32 random bits of one (pixel, sample, depth, dimension). */
static inline uint32_t lanes_random_bits(uint32_t pixel, uint32_t sample, uint32_t depth, uint32_t dimension)
{
    return lanes_hash32(lanes_hash32(lanes_hash32(lanes_hash32(pixel) + sample) + depth) + dimension);
}

/* vf_random for one (pixel, sample, depth, dimension): in [0, 1), a
 * multiple of 2^-24. */
static inline float lanes_random01(uint32_t pixel, uint32_t sample, uint32_t depth, uint32_t dimension)
{
    return (float)(lanes_random_bits(pixel, sample, depth, dimension) >> 8) * 0x1p-24f;
}

#endif
