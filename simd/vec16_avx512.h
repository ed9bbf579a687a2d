/* 16 lanes: native AVX-512 (F, DQ, BW, VL) with k-register masks.
 * Semantics: see vec1_scalar.h. */
#ifndef LANES_SIMD_VEC16_AVX512_H
#define LANES_SIMD_VEC16_AVX512_H

#if !defined(__AVX512F__) || !defined(__AVX512DQ__) || !defined(__AVX512BW__) || !defined(__AVX512VL__)
#error "vec16_avx512.h needs -mavx512f -mavx512dq -mavx512bw -mavx512vl"
#endif

#include <stdbool.h>
#include <stdint.h>
#include <immintrin.h>

typedef __m512 v16f;
typedef __m512i v16i;
typedef __mmask16 v16m;

/* Constructors */
static inline v16f v16f_zero(void) { return _mm512_setzero_ps(); }
static inline v16f v16f_set1(float x) { return _mm512_set1_ps(x); }
static inline v16i v16i_zero(void) { return _mm512_setzero_si512(); }
static inline v16i v16i_set1(int32_t x) { return _mm512_set1_epi32(x); }
static inline v16i v16i_iota(void)
{
    return _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
}
static inline v16m v16m_true(void) { return (v16m)0xffff; }
static inline v16m v16m_false(void) { return (v16m)0; }
static inline v16m v16m_first_n(size_t n) { return n >= 16 ? (v16m)0xffff : (v16m)((1u << n) - 1u); }
static inline v16m v16m_from_bits(uint32_t bits) { return (v16m)(bits & 0xffffu); }
static inline uint32_t v16m_bits(v16m a) { return (uint32_t)a; }

/* Load / store */
static inline v16f v16f_load(const float *p) { return _mm512_load_ps(p); }
static inline v16f v16f_loadu(const float *p) { return _mm512_loadu_ps(p); }
static inline v16f v16f_load_masked(v16m m, const float *p) { return _mm512_maskz_loadu_ps(m, p); }
static inline void v16f_store(float *p, v16f v) { _mm512_store_ps(p, v); }
static inline void v16f_storeu(float *p, v16f v) { _mm512_storeu_ps(p, v); }
static inline void v16f_store_masked(float *p, v16m m, v16f v) { _mm512_mask_storeu_ps(p, m, v); }
static inline v16i v16i_load(const int32_t *p) { return _mm512_load_si512((const void *)p); }
static inline v16i v16i_loadu(const int32_t *p) { return _mm512_loadu_si512((const void *)p); }
static inline void v16i_store(int32_t *p, v16i v) { _mm512_store_si512((void *)p, v); }
static inline void v16i_storeu(int32_t *p, v16i v) { _mm512_storeu_si512((void *)p, v); }
static inline void v16i_store_masked(int32_t *p, v16m m, v16i v) { _mm512_mask_storeu_epi32(p, m, v); }
/* An opmask store is a plain store with a mask: no read needed. */
static inline void v16f_store_merge(float *p, v16m m, v16f v) { _mm512_mask_storeu_ps(p, m, v); }
static inline void v16i_store_merge(int32_t *p, v16m m, v16i v) { _mm512_mask_storeu_epi32(p, m, v); }
static inline v16f v16f_gather(const float *base, v16i idx) { return _mm512_i32gather_ps(idx, base, 4); }
static inline v16i v16i_gather(const int32_t *base, v16i idx)
{
    return _mm512_i32gather_epi32(idx, base, 4);
}
/* Compress in a register, then a masked store of the first n lanes: the
 * memory form of VCOMPRESSPS is microcoded and slow on several cores. */
static inline int v16i_compress_store(int32_t *dst, v16m m, v16i v)
{
    int n = _mm_popcnt_u32((uint32_t)m);
    _mm512_mask_storeu_epi32(dst, v16m_first_n((size_t)n), _mm512_maskz_compress_epi32(m, v));
    return n;
}
static inline int v16f_compress_store(float *dst, v16m m, v16f v)
{
    int n = _mm_popcnt_u32((uint32_t)m);
    _mm512_mask_storeu_ps(dst, v16m_first_n((size_t)n), _mm512_maskz_compress_ps(m, v));
    return n;
}
static inline float v16f_lane(v16f v, int i)
{
    float tmp[16];
    _mm512_storeu_ps(tmp, v);
    return tmp[i & 15];
}
static inline int32_t v16i_lane(v16i v, int i)
{
    int32_t tmp[16];
    _mm512_storeu_si512((void *)tmp, v);
    return tmp[i & 15];
}

/* Arithmetic */
static inline v16f v16f_add(v16f a, v16f b) { return _mm512_add_ps(a, b); }
static inline v16f v16f_sub(v16f a, v16f b) { return _mm512_sub_ps(a, b); }
static inline v16f v16f_mul(v16f a, v16f b) { return _mm512_mul_ps(a, b); }
static inline v16f v16f_div(v16f a, v16f b) { return _mm512_div_ps(a, b); }
static inline v16f v16f_fmadd(v16f a, v16f b, v16f c) { return _mm512_fmadd_ps(a, b, c); }
static inline v16f v16f_fmsub(v16f a, v16f b, v16f c) { return _mm512_fmsub_ps(a, b, c); }
static inline v16f v16f_fnmadd(v16f a, v16f b, v16f c) { return _mm512_fnmadd_ps(a, b, c); }
static inline v16f v16f_min(v16f a, v16f b) { return _mm512_min_ps(a, b); }
static inline v16f v16f_max(v16f a, v16f b) { return _mm512_max_ps(a, b); }
static inline v16f v16f_abs(v16f a)
{
    return _mm512_castsi512_ps(_mm512_and_si512(_mm512_castps_si512(a), _mm512_set1_epi32(0x7fffffff)));
}
static inline v16f v16f_neg(v16f a)
{
    return _mm512_castsi512_ps(_mm512_xor_si512(_mm512_castps_si512(a), _mm512_set1_epi32((int32_t)0x80000000u)));
}
static inline v16f v16f_floor(v16f a) { return _mm512_roundscale_ps(a, _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC); }
static inline v16f v16f_sqrt(v16f a) { return _mm512_sqrt_ps(a); }
static inline v16f v16f_rcp(v16f a) { return _mm512_div_ps(_mm512_set1_ps(1.0f), a); }
/* VRCP14PS: about 14 bits, more than RCPPS's 12. */
static inline v16f v16f_rcp_fast(v16f a) { return _mm512_rcp14_ps(a); }
static inline v16f v16f_rcp_nr(v16f a)
{
    v16f r = _mm512_rcp14_ps(a);
    return _mm512_fmadd_ps(r, _mm512_fnmadd_ps(a, r, _mm512_set1_ps(1.0f)), r);
}
static inline v16i v16i_add(v16i a, v16i b) { return _mm512_add_epi32(a, b); }
static inline v16i v16i_sub(v16i a, v16i b) { return _mm512_sub_epi32(a, b); }
static inline v16i v16i_mul(v16i a, v16i b) { return _mm512_mullo_epi32(a, b); }
static inline v16i v16i_and(v16i a, v16i b) { return _mm512_and_si512(a, b); }
static inline v16i v16i_or(v16i a, v16i b) { return _mm512_or_si512(a, b); }
static inline v16i v16i_xor(v16i a, v16i b) { return _mm512_xor_si512(a, b); }
static inline v16i v16i_sll(v16i a, int n) { return _mm512_sll_epi32(a, _mm_cvtsi32_si128(n)); }
static inline v16i v16i_srl(v16i a, int n) { return _mm512_srl_epi32(a, _mm_cvtsi32_si128(n)); }
static inline v16i v16i_min(v16i a, v16i b) { return _mm512_min_epi32(a, b); }
static inline v16i v16i_max(v16i a, v16i b) { return _mm512_max_epi32(a, b); }

/* Conversions */
static inline v16i v16f_as_vi(v16f a) { return _mm512_castps_si512(a); }
static inline v16f v16i_as_vf(v16i a) { return _mm512_castsi512_ps(a); }
static inline v16f v16i_to_vf(v16i a) { return _mm512_cvtepi32_ps(a); }
static inline v16i v16f_to_vi(v16f a) { return _mm512_cvttps_epi32(a); }

/* Compare / mask */
static inline v16m v16f_lt(v16f a, v16f b) { return _mm512_cmp_ps_mask(a, b, _CMP_LT_OQ); }
static inline v16m v16f_le(v16f a, v16f b) { return _mm512_cmp_ps_mask(a, b, _CMP_LE_OQ); }
static inline v16m v16f_gt(v16f a, v16f b) { return _mm512_cmp_ps_mask(a, b, _CMP_GT_OQ); }
static inline v16m v16f_ge(v16f a, v16f b) { return _mm512_cmp_ps_mask(a, b, _CMP_GE_OQ); }
static inline v16m v16f_eq(v16f a, v16f b) { return _mm512_cmp_ps_mask(a, b, _CMP_EQ_OQ); }
static inline v16m v16f_neq(v16f a, v16f b) { return _mm512_cmp_ps_mask(a, b, _CMP_NEQ_UQ); }
static inline v16m v16f_isnan(v16f a) { return _mm512_cmp_ps_mask(a, a, _CMP_UNORD_Q); }
static inline v16m v16i_eq(v16i a, v16i b) { return _mm512_cmpeq_epi32_mask(a, b); }
static inline v16m v16i_lt(v16i a, v16i b) { return _mm512_cmplt_epi32_mask(a, b); }
static inline v16m v16i_gt(v16i a, v16i b) { return _mm512_cmpgt_epi32_mask(a, b); }
static inline v16m v16m_and(v16m a, v16m b) { return (v16m)(a & b); }
static inline v16m v16m_or(v16m a, v16m b) { return (v16m)(a | b); }
static inline v16m v16m_andnot(v16m a, v16m b) { return (v16m)(a & ~b); }
static inline v16m v16m_xor(v16m a, v16m b) { return (v16m)(a ^ b); }
static inline v16m v16m_not(v16m a) { return (v16m)~a; }
static inline bool v16m_any(v16m a) { return a != 0; }
static inline bool v16m_all(v16m a) { return a == 0xffff; }
static inline bool v16m_none(v16m a) { return a == 0; }
static inline int v16m_popcount(v16m a) { return _mm_popcnt_u32((uint32_t)a); }

/* Select: m ? a : b */
static inline v16f v16f_select(v16m m, v16f a, v16f b) { return _mm512_mask_blend_ps(m, b, a); }
static inline v16i v16i_select(v16m m, v16i a, v16i b) { return _mm512_mask_blend_epi32(m, b, a); }

/* Reductions (NaN-free input) */
static inline float v16f_reduce_min(v16f a) { return _mm512_reduce_min_ps(a); }
static inline float v16f_reduce_max(v16f a) { return _mm512_reduce_max_ps(a); }
static inline float v16f_reduce_add(v16f a) { return _mm512_reduce_add_ps(a); }

#endif
