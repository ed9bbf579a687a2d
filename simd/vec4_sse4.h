/* 4 lanes: SSE4.1 (plus POPCNT). Masks are vectors with all bits of an
 * active lane set. SSE has no masked load or store, so those walk the mask;
 * the kernels use them only off their hot paths. Semantics: see
 * vec1_scalar.h. */
#ifndef LANES_SIMD_VEC4_SSE4_H
#define LANES_SIMD_VEC4_SSE4_H

#if !defined(__SSE4_1__) || !defined(__POPCNT__)
#error "vec4_sse4.h needs -msse4.1 -mpopcnt"
#endif

#include <stdbool.h>
#include <stdint.h>
#include <string.h>
#include <smmintrin.h>
#include <nmmintrin.h>

typedef __m128 v4f;
typedef __m128i v4i;
typedef __m128 v4m;

/* Constructors */
static inline v4f v4f_zero(void) { return _mm_setzero_ps(); }
static inline v4f v4f_set1(float x) { return _mm_set1_ps(x); }
static inline v4i v4i_zero(void) { return _mm_setzero_si128(); }
static inline v4i v4i_set1(int32_t x) { return _mm_set1_epi32(x); }
static inline v4i v4i_iota(void) { return _mm_setr_epi32(0, 1, 2, 3); }
static inline v4m v4m_true(void) { return _mm_castsi128_ps(_mm_set1_epi32(-1)); }
static inline v4m v4m_false(void) { return _mm_setzero_ps(); }
static inline v4m v4m_first_n(size_t n)
{
    int32_t k = n > 4 ? 4 : (int32_t)n;
    return _mm_castsi128_ps(_mm_cmpgt_epi32(_mm_set1_epi32(k), v4i_iota()));
}
static inline v4m v4m_from_bits(uint32_t bits)
{
    __m128i sel = _mm_setr_epi32(1, 2, 4, 8);
    __m128i b = _mm_and_si128(_mm_set1_epi32((int32_t)bits), sel);
    return _mm_castsi128_ps(_mm_cmpeq_epi32(b, sel));
}
static inline uint32_t v4m_bits(v4m a) { return (uint32_t)_mm_movemask_ps(a); }

/* Load / store */
static inline v4f v4f_load(const float *p) { return _mm_load_ps(p); }
static inline v4f v4f_loadu(const float *p) { return _mm_loadu_ps(p); }
static inline v4f v4f_load_masked(v4m m, const float *p)
{
    float tmp[4] = {0.0f, 0.0f, 0.0f, 0.0f};
    uint32_t bits = v4m_bits(m);
    for (int i = 0; i < 4; i++)
        if (bits & (1u << i)) tmp[i] = p[i];
    return _mm_loadu_ps(tmp);
}
static inline void v4f_store(float *p, v4f v) { _mm_store_ps(p, v); }
static inline void v4f_storeu(float *p, v4f v) { _mm_storeu_ps(p, v); }
static inline void v4f_store_masked(float *p, v4m m, v4f v)
{
    float tmp[4];
    uint32_t bits = v4m_bits(m);
    _mm_storeu_ps(tmp, v);
    for (int i = 0; i < 4; i++)
        if (bits & (1u << i)) p[i] = tmp[i];
}
static inline v4i v4i_load(const int32_t *p) { return _mm_load_si128((const __m128i *)p); }
static inline v4i v4i_loadu(const int32_t *p) { return _mm_loadu_si128((const __m128i *)p); }
static inline void v4i_store(int32_t *p, v4i v) { _mm_store_si128((__m128i *)p, v); }
static inline void v4i_storeu(int32_t *p, v4i v) { _mm_storeu_si128((__m128i *)p, v); }
static inline void v4i_store_masked(int32_t *p, v4m m, v4i v)
{
    int32_t tmp[4];
    uint32_t bits = v4m_bits(m);
    _mm_storeu_si128((__m128i *)tmp, v);
    for (int i = 0; i < 4; i++)
        if (bits & (1u << i)) p[i] = tmp[i];
}
/* SSE's only masked store is the non-temporal MASKMOVDQU; a load, a blend
 * and a store replace store_masked's lane-by-lane loop. */
static inline void v4f_store_merge(float *p, v4m m, v4f v)
{
    _mm_storeu_ps(p, _mm_blendv_ps(_mm_loadu_ps(p), v, m));
}
static inline void v4i_store_merge(int32_t *p, v4m m, v4i v)
{
    __m128i old = _mm_loadu_si128((const __m128i *)(const void *)p);
    _mm_storeu_si128((__m128i *)(void *)p, _mm_blendv_epi8(old, v, _mm_castps_si128(m)));
}
static inline v4f v4f_gather(const float *base, v4i idx)
{
    return _mm_setr_ps(base[_mm_cvtsi128_si32(idx)], base[_mm_extract_epi32(idx, 1)],
                       base[_mm_extract_epi32(idx, 2)], base[_mm_extract_epi32(idx, 3)]);
}
static inline v4i v4i_gather(const int32_t *base, v4i idx)
{
    return _mm_setr_epi32(base[_mm_cvtsi128_si32(idx)], base[_mm_extract_epi32(idx, 1)],
                          base[_mm_extract_epi32(idx, 2)], base[_mm_extract_epi32(idx, 3)]);
}
/* pshufb controls that move the active lanes of a 4-bit mask to the front. */
static inline __m128i v4_compress_shuffle(uint32_t bits)
{
    _Alignas(16) static const uint8_t table[16][16] = {
        {0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3},
        {0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3},
        {4, 5, 6, 7, 0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3},
        {0, 1, 2, 3, 4, 5, 6, 7, 0, 1, 2, 3, 0, 1, 2, 3},
        {8, 9, 10, 11, 0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3},
        {0, 1, 2, 3, 8, 9, 10, 11, 0, 1, 2, 3, 0, 1, 2, 3},
        {4, 5, 6, 7, 8, 9, 10, 11, 0, 1, 2, 3, 0, 1, 2, 3},
        {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 0, 1, 2, 3},
        {12, 13, 14, 15, 0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3},
        {0, 1, 2, 3, 12, 13, 14, 15, 0, 1, 2, 3, 0, 1, 2, 3},
        {4, 5, 6, 7, 12, 13, 14, 15, 0, 1, 2, 3, 0, 1, 2, 3},
        {0, 1, 2, 3, 4, 5, 6, 7, 12, 13, 14, 15, 0, 1, 2, 3},
        {8, 9, 10, 11, 12, 13, 14, 15, 0, 1, 2, 3, 0, 1, 2, 3},
        {0, 1, 2, 3, 8, 9, 10, 11, 12, 13, 14, 15, 0, 1, 2, 3},
        {4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 0, 1, 2, 3},
        {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15},
    };
    return _mm_load_si128((const __m128i *)(const void *)table[bits & 15u]);
}
static inline int v4i_compress_store(int32_t *dst, v4m m, v4i v)
{
    uint32_t bits = v4m_bits(m);
    int n = _mm_popcnt_u32(bits);
    int32_t tmp[4];
    _mm_storeu_si128((__m128i *)tmp, _mm_shuffle_epi8(v, v4_compress_shuffle(bits)));
    memcpy(dst, tmp, (size_t)n * sizeof(int32_t));
    return n;
}
static inline int v4f_compress_store(float *dst, v4m m, v4f v)
{
    return v4i_compress_store((int32_t *)(void *)dst, m, _mm_castps_si128(v));
}
static inline float v4f_lane(v4f v, int i)
{
    float tmp[4];
    _mm_storeu_ps(tmp, v);
    return tmp[i & 3];
}
static inline int32_t v4i_lane(v4i v, int i)
{
    int32_t tmp[4];
    _mm_storeu_si128((__m128i *)tmp, v);
    return tmp[i & 3];
}

/* Arithmetic */
static inline v4f v4f_add(v4f a, v4f b) { return _mm_add_ps(a, b); }
static inline v4f v4f_sub(v4f a, v4f b) { return _mm_sub_ps(a, b); }
static inline v4f v4f_mul(v4f a, v4f b) { return _mm_mul_ps(a, b); }
static inline v4f v4f_div(v4f a, v4f b) { return _mm_div_ps(a, b); }
/* No FMA on this set: two roundings. */
static inline v4f v4f_fmadd(v4f a, v4f b, v4f c) { return _mm_add_ps(_mm_mul_ps(a, b), c); }
static inline v4f v4f_fmsub(v4f a, v4f b, v4f c) { return _mm_sub_ps(_mm_mul_ps(a, b), c); }
static inline v4f v4f_fnmadd(v4f a, v4f b, v4f c) { return _mm_sub_ps(c, _mm_mul_ps(a, b)); }
static inline v4f v4f_min(v4f a, v4f b) { return _mm_min_ps(a, b); }
static inline v4f v4f_max(v4f a, v4f b) { return _mm_max_ps(a, b); }
static inline v4f v4f_abs(v4f a) { return _mm_and_ps(a, _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff))); }
static inline v4f v4f_neg(v4f a) { return _mm_xor_ps(a, _mm_set1_ps(-0.0f)); }
static inline v4f v4f_floor(v4f a) { return _mm_floor_ps(a); }
static inline v4f v4f_sqrt(v4f a) { return _mm_sqrt_ps(a); }
static inline v4f v4f_rcp(v4f a) { return _mm_div_ps(_mm_set1_ps(1.0f), a); }
static inline v4f v4f_rcp_fast(v4f a) { return _mm_rcp_ps(a); }
static inline v4f v4f_rcp_nr(v4f a)
{
    v4f r = _mm_rcp_ps(a);
    return _mm_add_ps(r, _mm_mul_ps(r, _mm_sub_ps(_mm_set1_ps(1.0f), _mm_mul_ps(a, r))));
}
static inline v4i v4i_add(v4i a, v4i b) { return _mm_add_epi32(a, b); }
static inline v4i v4i_sub(v4i a, v4i b) { return _mm_sub_epi32(a, b); }
static inline v4i v4i_mul(v4i a, v4i b) { return _mm_mullo_epi32(a, b); }
static inline v4i v4i_and(v4i a, v4i b) { return _mm_and_si128(a, b); }
static inline v4i v4i_or(v4i a, v4i b) { return _mm_or_si128(a, b); }
static inline v4i v4i_xor(v4i a, v4i b) { return _mm_xor_si128(a, b); }
static inline v4i v4i_sll(v4i a, int n) { return _mm_sll_epi32(a, _mm_cvtsi32_si128(n)); }
static inline v4i v4i_srl(v4i a, int n) { return _mm_srl_epi32(a, _mm_cvtsi32_si128(n)); }
static inline v4i v4i_min(v4i a, v4i b) { return _mm_min_epi32(a, b); }
static inline v4i v4i_max(v4i a, v4i b) { return _mm_max_epi32(a, b); }

/* Conversions */
static inline v4i v4f_as_vi(v4f a) { return _mm_castps_si128(a); }
static inline v4f v4i_as_vf(v4i a) { return _mm_castsi128_ps(a); }
static inline v4f v4i_to_vf(v4i a) { return _mm_cvtepi32_ps(a); }
static inline v4i v4f_to_vi(v4f a) { return _mm_cvttps_epi32(a); }

/* Compare / mask */
static inline v4m v4f_lt(v4f a, v4f b) { return _mm_cmplt_ps(a, b); }
static inline v4m v4f_le(v4f a, v4f b) { return _mm_cmple_ps(a, b); }
static inline v4m v4f_gt(v4f a, v4f b) { return _mm_cmpgt_ps(a, b); }
static inline v4m v4f_ge(v4f a, v4f b) { return _mm_cmpge_ps(a, b); }
static inline v4m v4f_eq(v4f a, v4f b) { return _mm_cmpeq_ps(a, b); }
static inline v4m v4f_neq(v4f a, v4f b) { return _mm_cmpneq_ps(a, b); }
static inline v4m v4f_isnan(v4f a) { return _mm_cmpunord_ps(a, a); }
static inline v4m v4i_eq(v4i a, v4i b) { return _mm_castsi128_ps(_mm_cmpeq_epi32(a, b)); }
static inline v4m v4i_lt(v4i a, v4i b) { return _mm_castsi128_ps(_mm_cmplt_epi32(a, b)); }
static inline v4m v4i_gt(v4i a, v4i b) { return _mm_castsi128_ps(_mm_cmpgt_epi32(a, b)); }
static inline v4m v4m_and(v4m a, v4m b) { return _mm_and_ps(a, b); }
static inline v4m v4m_or(v4m a, v4m b) { return _mm_or_ps(a, b); }
static inline v4m v4m_andnot(v4m a, v4m b) { return _mm_andnot_ps(b, a); }
static inline v4m v4m_xor(v4m a, v4m b) { return _mm_xor_ps(a, b); }
static inline v4m v4m_not(v4m a) { return _mm_xor_ps(a, v4m_true()); }
static inline bool v4m_any(v4m a) { return _mm_movemask_ps(a) != 0; }
static inline bool v4m_all(v4m a) { return _mm_movemask_ps(a) == 15; }
static inline bool v4m_none(v4m a) { return _mm_movemask_ps(a) == 0; }
static inline int v4m_popcount(v4m a) { return _mm_popcnt_u32(v4m_bits(a)); }

/* Select: m ? a : b */
static inline v4f v4f_select(v4m m, v4f a, v4f b) { return _mm_blendv_ps(b, a, m); }
static inline v4i v4i_select(v4m m, v4i a, v4i b)
{
    return _mm_castps_si128(_mm_blendv_ps(_mm_castsi128_ps(b), _mm_castsi128_ps(a), m));
}

/* Reductions (NaN-free input) */
static inline float v4f_reduce_min(v4f a)
{
    a = _mm_min_ps(a, _mm_shuffle_ps(a, a, _MM_SHUFFLE(1, 0, 3, 2)));
    a = _mm_min_ps(a, _mm_shuffle_ps(a, a, _MM_SHUFFLE(2, 3, 0, 1)));
    return _mm_cvtss_f32(a);
}
static inline float v4f_reduce_max(v4f a)
{
    a = _mm_max_ps(a, _mm_shuffle_ps(a, a, _MM_SHUFFLE(1, 0, 3, 2)));
    a = _mm_max_ps(a, _mm_shuffle_ps(a, a, _MM_SHUFFLE(2, 3, 0, 1)));
    return _mm_cvtss_f32(a);
}
static inline float v4f_reduce_add(v4f a)
{
    a = _mm_add_ps(a, _mm_shuffle_ps(a, a, _MM_SHUFFLE(1, 0, 3, 2)));
    a = _mm_add_ps(a, _mm_shuffle_ps(a, a, _MM_SHUFFLE(2, 3, 0, 1)));
    return _mm_cvtss_f32(a);
}

#endif
