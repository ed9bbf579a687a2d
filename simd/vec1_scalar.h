/* 1 lane: the scalar backend. Plain C floats; it is compiled with the x86-64
 * baseline flags, so it runs on every x86-64 CPU. It exists so that the
 * width-generic kernels also compile as ordinary scalar code, the baseline
 * every wider set is measured against.
 *
 * Semantics shared by every backend (and relied on by the kernels):
 * - min(a, b) = a < b ? a : b and max(a, b) = a > b ? a : b: when either
 *   operand is NaN the SECOND operand is returned (x86 MINPS/MAXPS).
 * - fmadd without FMA hardware is a multiply and an add, rounded twice.
 * - Compares are ordered (false on NaN) except neq, which is true on NaN.
 * - Masked loads read 0 in inactive lanes and touch no memory there; masked
 *   stores and compress stores write active lanes only.
 * - store_merge(p, m, v) leaves p[i] = m[i] ? v[i] : p[i] for all W
 *   elements, and may do it by reading and rewriting every one of them:
 *   each must lie in bounds and be written by no other thread meanwhile.
 *   With vector masks (sse4, avx, avx2) it is a load, a blend and a
 *   store, cheaper than a masked store on AMD Zen 3 (vec8_avx.h); with
 *   opmasks it is the masked store.
 * - Mask bits: lane i is bit i.
 * - Integer add, sub and mul wrap modulo 2^32 (mul keeps the low 32 bits of
 *   the product); srl shifts in zeros.
 * - floor rounds toward -inf, keeping -0, infinities and NaN (quieted). */
#ifndef LANES_SIMD_VEC1_SCALAR_H
#define LANES_SIMD_VEC1_SCALAR_H

#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <string.h>
#include <xmmintrin.h>

typedef float v1f;
typedef int32_t v1i;
typedef bool v1m;

/* Constructors */
static inline v1f v1f_zero(void) { return 0.0f; }
static inline v1f v1f_set1(float x) { return x; }
static inline v1i v1i_zero(void) { return 0; }
static inline v1i v1i_set1(int32_t x) { return x; }
static inline v1i v1i_iota(void) { return 0; }
static inline v1m v1m_true(void) { return true; }
static inline v1m v1m_false(void) { return false; }
static inline v1m v1m_first_n(size_t n) { return n > 0; }
static inline v1m v1m_from_bits(uint32_t bits) { return (bits & 1u) != 0; }

/* Load / store */
static inline v1f v1f_load(const float *p) { return *p; }
static inline v1f v1f_loadu(const float *p) { return *p; }
static inline v1f v1f_load_masked(v1m m, const float *p) { return m ? *p : 0.0f; }
static inline void v1f_store(float *p, v1f v) { *p = v; }
static inline void v1f_storeu(float *p, v1f v) { *p = v; }
static inline void v1f_store_masked(float *p, v1m m, v1f v) { if (m) *p = v; }
static inline v1i v1i_load(const int32_t *p) { return *p; }
static inline v1i v1i_loadu(const int32_t *p) { return *p; }
static inline void v1i_store(int32_t *p, v1i v) { *p = v; }
static inline void v1i_storeu(int32_t *p, v1i v) { *p = v; }
static inline void v1i_store_masked(int32_t *p, v1m m, v1i v) { if (m) *p = v; }
static inline void v1f_store_merge(float *p, v1m m, v1f v) { if (m) *p = v; }
static inline void v1i_store_merge(int32_t *p, v1m m, v1i v) { if (m) *p = v; }
static inline v1f v1f_gather(const float *base, v1i idx) { return base[idx]; }
static inline v1i v1i_gather(const int32_t *base, v1i idx) { return base[idx]; }
static inline int v1f_compress_store(float *dst, v1m m, v1f v)
{
    if (m) *dst = v;
    return m ? 1 : 0;
}
static inline int v1i_compress_store(int32_t *dst, v1m m, v1i v)
{
    if (m) *dst = v;
    return m ? 1 : 0;
}
static inline float v1f_lane(v1f v, int i) { (void)i; return v; }
static inline int32_t v1i_lane(v1i v, int i) { (void)i; return v; }

/* Arithmetic */
static inline v1f v1f_add(v1f a, v1f b) { return a + b; }
static inline v1f v1f_sub(v1f a, v1f b) { return a - b; }
static inline v1f v1f_mul(v1f a, v1f b) { return a * b; }
static inline v1f v1f_div(v1f a, v1f b) { return a / b; }
static inline v1f v1f_fmadd(v1f a, v1f b, v1f c) { return a * b + c; }
static inline v1f v1f_fmsub(v1f a, v1f b, v1f c) { return a * b - c; }
static inline v1f v1f_fnmadd(v1f a, v1f b, v1f c) { return c - a * b; }
static inline v1f v1f_min(v1f a, v1f b) { return a < b ? a : b; }
static inline v1f v1f_max(v1f a, v1f b) { return a > b ? a : b; }
static inline v1f v1f_abs(v1f a)
{
    uint32_t u;
    memcpy(&u, &a, 4);
    u &= 0x7fffffffu;
    memcpy(&a, &u, 4);
    return a;
}
static inline v1f v1f_neg(v1f a) { return -a; }
/* The baseline has no ROUNDSS (SSE4.1): libm's floorf. */
static inline v1f v1f_floor(v1f a) { return floorf(a); }
static inline v1f v1f_sqrt(v1f a) { return _mm_cvtss_f32(_mm_sqrt_ss(_mm_set_ss(a))); }
static inline v1f v1f_rcp(v1f a) { return 1.0f / a; }
/* RCPSS: about 12 bits. */
static inline v1f v1f_rcp_fast(v1f a) { return _mm_cvtss_f32(_mm_rcp_ss(_mm_set_ss(a))); }
static inline v1f v1f_rcp_nr(v1f a)
{
    v1f r = v1f_rcp_fast(a);
    return r + r * (1.0f - a * r);
}
static inline v1i v1i_add(v1i a, v1i b) { return (v1i)((uint32_t)a + (uint32_t)b); }
static inline v1i v1i_sub(v1i a, v1i b) { return (v1i)((uint32_t)a - (uint32_t)b); }
static inline v1i v1i_mul(v1i a, v1i b) { return (v1i)((uint32_t)a * (uint32_t)b); }
static inline v1i v1i_and(v1i a, v1i b) { return a & b; }
static inline v1i v1i_or(v1i a, v1i b) { return a | b; }
static inline v1i v1i_xor(v1i a, v1i b) { return a ^ b; }
static inline v1i v1i_sll(v1i a, int n) { return (v1i)((uint32_t)a << n); }
static inline v1i v1i_srl(v1i a, int n) { return (v1i)((uint32_t)a >> n); }
static inline v1i v1i_min(v1i a, v1i b) { return a < b ? a : b; }
static inline v1i v1i_max(v1i a, v1i b) { return a > b ? a : b; }

/* Conversions */
static inline v1i v1f_as_vi(v1f a) { v1i r; memcpy(&r, &a, 4); return r; }
static inline v1f v1i_as_vf(v1i a) { v1f r; memcpy(&r, &a, 4); return r; }
static inline v1f v1i_to_vf(v1i a) { return (float)a; }
static inline v1i v1f_to_vi(v1f a) { return _mm_cvttss_si32(_mm_set_ss(a)); }

/* Compare / mask */
static inline v1m v1f_lt(v1f a, v1f b) { return a < b; }
static inline v1m v1f_le(v1f a, v1f b) { return a <= b; }
static inline v1m v1f_gt(v1f a, v1f b) { return a > b; }
static inline v1m v1f_ge(v1f a, v1f b) { return a >= b; }
static inline v1m v1f_eq(v1f a, v1f b) { return a == b; }
static inline v1m v1f_neq(v1f a, v1f b) { return !(a == b); }
static inline v1m v1f_isnan(v1f a) { return a != a; }
static inline v1m v1i_eq(v1i a, v1i b) { return a == b; }
static inline v1m v1i_lt(v1i a, v1i b) { return a < b; }
static inline v1m v1i_gt(v1i a, v1i b) { return a > b; }
static inline v1m v1m_and(v1m a, v1m b) { return a && b; }
static inline v1m v1m_or(v1m a, v1m b) { return a || b; }
static inline v1m v1m_andnot(v1m a, v1m b) { return a && !b; }
static inline v1m v1m_xor(v1m a, v1m b) { return a != b; }
static inline v1m v1m_not(v1m a) { return !a; }
static inline bool v1m_any(v1m a) { return a; }
static inline bool v1m_all(v1m a) { return a; }
static inline bool v1m_none(v1m a) { return !a; }
static inline uint32_t v1m_bits(v1m a) { return a ? 1u : 0u; }
static inline int v1m_popcount(v1m a) { return a ? 1 : 0; }

/* Select */
static inline v1f v1f_select(v1m m, v1f a, v1f b) { return m ? a : b; }
static inline v1i v1i_select(v1m m, v1i a, v1i b) { return m ? a : b; }

/* Reductions */
static inline float v1f_reduce_min(v1f a) { return a; }
static inline float v1f_reduce_max(v1f a) { return a; }
static inline float v1f_reduce_add(v1f a) { return a; }

#endif
