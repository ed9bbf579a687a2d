/* 8 lanes with AVX-512VL: ymm registers, opmask (k register) compares,
 * blends, masked loads and stores and in-register compress: the avx512vl8
 * set. Beside avx2 (8 lanes, vector masks) and avx512 (16 lanes, opmasks) it
 * separates what the instruction set brings from what the width brings.
 * Rounding matches the other FMA sets; the fast reciprocal is VRCP14PS, as
 * in avx512. Semantics: see vec1_scalar.h. */
#ifndef LANES_SIMD_VEC8_AVX512VL_H
#define LANES_SIMD_VEC8_AVX512VL_H

#if !defined(__AVX512F__) || !defined(__AVX512VL__) || !defined(__AVX512DQ__) || !defined(__FMA__)
#error "vec8_avx512vl.h needs -mavx512f -mavx512vl -mavx512dq -mfma"
#endif

#include <stdbool.h>
#include <stdint.h>
#include <immintrin.h>

#include "vec4_sse4.h" /* the reductions, shared with vec8_avx.h for equal rounding */

typedef __m256 v8f;
typedef __m256i v8i;
typedef __mmask8 v8m;

/* Constructors */
static inline v8f v8f_zero(void) { return _mm256_setzero_ps(); }
static inline v8f v8f_set1(float x) { return _mm256_set1_ps(x); }
static inline v8i v8i_zero(void) { return _mm256_setzero_si256(); }
static inline v8i v8i_set1(int32_t x) { return _mm256_set1_epi32(x); }
static inline v8i v8i_iota(void) { return _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7); }
static inline v8m v8m_true(void) { return (v8m)0xff; }
static inline v8m v8m_false(void) { return (v8m)0; }
static inline v8m v8m_first_n(size_t n) { return n >= 8 ? (v8m)0xff : (v8m)((1u << n) - 1u); }
static inline v8m v8m_from_bits(uint32_t bits) { return (v8m)(bits & 0xffu); }
static inline uint32_t v8m_bits(v8m a) { return (uint32_t)a; }

/* Load / store */
static inline v8f v8f_load(const float *p) { return _mm256_load_ps(p); }
static inline v8f v8f_loadu(const float *p) { return _mm256_loadu_ps(p); }
static inline v8f v8f_load_masked(v8m m, const float *p) { return _mm256_maskz_loadu_ps(m, p); }
static inline void v8f_store(float *p, v8f v) { _mm256_store_ps(p, v); }
static inline void v8f_storeu(float *p, v8f v) { _mm256_storeu_ps(p, v); }
static inline void v8f_store_masked(float *p, v8m m, v8f v) { _mm256_mask_storeu_ps(p, m, v); }
static inline v8i v8i_load(const int32_t *p) { return _mm256_load_si256((const __m256i *)p); }
static inline v8i v8i_loadu(const int32_t *p) { return _mm256_loadu_si256((const __m256i *)p); }
static inline void v8i_store(int32_t *p, v8i v) { _mm256_store_si256((__m256i *)p, v); }
static inline void v8i_storeu(int32_t *p, v8i v) { _mm256_storeu_si256((__m256i *)p, v); }
static inline void v8i_store_masked(int32_t *p, v8m m, v8i v) { _mm256_mask_storeu_epi32(p, m, v); }
static inline v8f v8f_gather(const float *base, v8i idx) { return _mm256_i32gather_ps(base, idx, 4); }
static inline v8i v8i_gather(const int32_t *base, v8i idx)
{
    return _mm256_i32gather_epi32(base, idx, 4);
}
/* Compress in a register, then a masked store of the first n lanes (the
 * memory form of VCOMPRESSPS is microcoded on several cores). */
static inline int v8i_compress_store(int32_t *dst, v8m m, v8i v)
{
    int n = _mm_popcnt_u32((uint32_t)m);
    _mm256_mask_storeu_epi32(dst, v8m_first_n((size_t)n), _mm256_maskz_compress_epi32(m, v));
    return n;
}
static inline int v8f_compress_store(float *dst, v8m m, v8f v)
{
    int n = _mm_popcnt_u32((uint32_t)m);
    _mm256_mask_storeu_ps(dst, v8m_first_n((size_t)n), _mm256_maskz_compress_ps(m, v));
    return n;
}
static inline float v8f_lane(v8f v, int i)
{
    float tmp[8];
    _mm256_storeu_ps(tmp, v);
    return tmp[i & 7];
}
static inline int32_t v8i_lane(v8i v, int i)
{
    int32_t tmp[8];
    _mm256_storeu_si256((__m256i *)tmp, v);
    return tmp[i & 7];
}

/* Arithmetic */
static inline v8f v8f_add(v8f a, v8f b) { return _mm256_add_ps(a, b); }
static inline v8f v8f_sub(v8f a, v8f b) { return _mm256_sub_ps(a, b); }
static inline v8f v8f_mul(v8f a, v8f b) { return _mm256_mul_ps(a, b); }
static inline v8f v8f_div(v8f a, v8f b) { return _mm256_div_ps(a, b); }
static inline v8f v8f_fmadd(v8f a, v8f b, v8f c) { return _mm256_fmadd_ps(a, b, c); }
static inline v8f v8f_fmsub(v8f a, v8f b, v8f c) { return _mm256_fmsub_ps(a, b, c); }
static inline v8f v8f_fnmadd(v8f a, v8f b, v8f c) { return _mm256_fnmadd_ps(a, b, c); }
static inline v8f v8f_min(v8f a, v8f b) { return _mm256_min_ps(a, b); }
static inline v8f v8f_max(v8f a, v8f b) { return _mm256_max_ps(a, b); }
static inline v8f v8f_abs(v8f a)
{
    return _mm256_castsi256_ps(_mm256_and_si256(_mm256_castps_si256(a), _mm256_set1_epi32(0x7fffffff)));
}
static inline v8f v8f_neg(v8f a)
{
    return _mm256_castsi256_ps(_mm256_xor_si256(_mm256_castps_si256(a), _mm256_set1_epi32((int32_t)0x80000000u)));
}
static inline v8f v8f_sqrt(v8f a) { return _mm256_sqrt_ps(a); }
static inline v8f v8f_rcp(v8f a) { return _mm256_div_ps(_mm256_set1_ps(1.0f), a); }
/* VRCP14PS: about 14 bits, more than RCPPS's 12. */
static inline v8f v8f_rcp_fast(v8f a) { return _mm256_rcp14_ps(a); }
static inline v8f v8f_rcp_nr(v8f a)
{
    v8f r = _mm256_rcp14_ps(a);
    return _mm256_fmadd_ps(r, _mm256_fnmadd_ps(a, r, _mm256_set1_ps(1.0f)), r);
}
static inline v8i v8i_add(v8i a, v8i b) { return _mm256_add_epi32(a, b); }
static inline v8i v8i_sub(v8i a, v8i b) { return _mm256_sub_epi32(a, b); }
static inline v8i v8i_and(v8i a, v8i b) { return _mm256_and_si256(a, b); }
static inline v8i v8i_or(v8i a, v8i b) { return _mm256_or_si256(a, b); }
static inline v8i v8i_xor(v8i a, v8i b) { return _mm256_xor_si256(a, b); }
static inline v8i v8i_sll(v8i a, int n) { return _mm256_sll_epi32(a, _mm_cvtsi32_si128(n)); }
static inline v8i v8i_srl(v8i a, int n) { return _mm256_srl_epi32(a, _mm_cvtsi32_si128(n)); }
static inline v8i v8i_min(v8i a, v8i b) { return _mm256_min_epi32(a, b); }
static inline v8i v8i_max(v8i a, v8i b) { return _mm256_max_epi32(a, b); }

/* Conversions */
static inline v8i v8f_as_vi(v8f a) { return _mm256_castps_si256(a); }
static inline v8f v8i_as_vf(v8i a) { return _mm256_castsi256_ps(a); }
static inline v8f v8i_to_vf(v8i a) { return _mm256_cvtepi32_ps(a); }
static inline v8i v8f_to_vi(v8f a) { return _mm256_cvttps_epi32(a); }

/* Compare / mask */
static inline v8m v8f_lt(v8f a, v8f b) { return _mm256_cmp_ps_mask(a, b, _CMP_LT_OQ); }
static inline v8m v8f_le(v8f a, v8f b) { return _mm256_cmp_ps_mask(a, b, _CMP_LE_OQ); }
static inline v8m v8f_gt(v8f a, v8f b) { return _mm256_cmp_ps_mask(a, b, _CMP_GT_OQ); }
static inline v8m v8f_ge(v8f a, v8f b) { return _mm256_cmp_ps_mask(a, b, _CMP_GE_OQ); }
static inline v8m v8f_eq(v8f a, v8f b) { return _mm256_cmp_ps_mask(a, b, _CMP_EQ_OQ); }
static inline v8m v8f_neq(v8f a, v8f b) { return _mm256_cmp_ps_mask(a, b, _CMP_NEQ_UQ); }
static inline v8m v8f_isnan(v8f a) { return _mm256_cmp_ps_mask(a, a, _CMP_UNORD_Q); }
static inline v8m v8i_eq(v8i a, v8i b) { return _mm256_cmpeq_epi32_mask(a, b); }
static inline v8m v8i_lt(v8i a, v8i b) { return _mm256_cmplt_epi32_mask(a, b); }
static inline v8m v8i_gt(v8i a, v8i b) { return _mm256_cmpgt_epi32_mask(a, b); }
static inline v8m v8m_and(v8m a, v8m b) { return (v8m)(a & b); }
static inline v8m v8m_or(v8m a, v8m b) { return (v8m)(a | b); }
static inline v8m v8m_andnot(v8m a, v8m b) { return (v8m)(a & ~b); }
static inline v8m v8m_xor(v8m a, v8m b) { return (v8m)(a ^ b); }
static inline v8m v8m_not(v8m a) { return (v8m)~a; }
static inline bool v8m_any(v8m a) { return a != 0; }
static inline bool v8m_all(v8m a) { return a == 0xff; }
static inline bool v8m_none(v8m a) { return a == 0; }
static inline int v8m_popcount(v8m a) { return _mm_popcnt_u32((uint32_t)a); }

/* Select: m ? a : b */
static inline v8f v8f_select(v8m m, v8f a, v8f b) { return _mm256_mask_blend_ps(m, b, a); }
static inline v8i v8i_select(v8m m, v8i a, v8i b) { return _mm256_mask_blend_epi32(m, b, a); }

/* Reductions (NaN-free input), in vec8_avx.h's order */
static inline float v8f_reduce_min(v8f a)
{
    return v4f_reduce_min(_mm_min_ps(_mm256_castps256_ps128(a), _mm256_extractf128_ps(a, 1)));
}
static inline float v8f_reduce_max(v8f a)
{
    return v4f_reduce_max(_mm_max_ps(_mm256_castps256_ps128(a), _mm256_extractf128_ps(a, 1)));
}
static inline float v8f_reduce_add(v8f a)
{
    return v4f_reduce_add(_mm_add_ps(_mm256_castps256_ps128(a), _mm256_extractf128_ps(a, 1)));
}

#endif
