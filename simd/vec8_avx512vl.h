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

#include "vec8_ymm.h" /* all that takes no mask, shared with avx and avx2 */

typedef __mmask8 v8m;

/* Masks */
static inline v8m v8m_true(void) { return (v8m)0xff; }
static inline v8m v8m_false(void) { return (v8m)0; }
static inline v8m v8m_first_n(size_t n) { return n >= 8 ? (v8m)0xff : (v8m)((1u << n) - 1u); }
static inline v8m v8m_from_bits(uint32_t bits) { return (v8m)(bits & 0xffu); }
static inline uint32_t v8m_bits(v8m a) { return (uint32_t)a; }

/* Masked load / store, compress */
static inline v8f v8f_load_masked(v8m m, const float *p) { return _mm256_maskz_loadu_ps(m, p); }
static inline void v8f_store_masked(float *p, v8m m, v8f v) { _mm256_mask_storeu_ps(p, m, v); }
static inline void v8i_store_masked(int32_t *p, v8m m, v8i v) { _mm256_mask_storeu_epi32(p, m, v); }
/* An opmask store is a plain store with a mask: no read needed. */
static inline void v8f_store_merge(float *p, v8m m, v8f v) { _mm256_mask_storeu_ps(p, m, v); }
static inline void v8i_store_merge(int32_t *p, v8m m, v8i v) { _mm256_mask_storeu_epi32(p, m, v); }
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

/* The fast reciprocal: VRCP14PS, about 14 bits, more than RCPPS's 12 */
static inline v8f v8f_rcp_fast(v8f a) { return _mm256_rcp14_ps(a); }
static inline v8f v8f_rcp_nr(v8f a)
{
    v8f r = _mm256_rcp14_ps(a);
    return _mm256_fmadd_ps(r, _mm256_fnmadd_ps(a, r, _mm256_set1_ps(1.0f)), r);
}

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

#endif
