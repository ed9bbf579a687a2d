/* What every 8-lane set does alike on ymm registers, whatever its masks:
 * the float and integer vectors, constructors, plain loads and stores,
 * gathers, arithmetic, conversions and reductions. The sets differ in their
 * masks and what takes a mask (compares, blends, masked memory, compress,
 * the fast reciprocal): vector masks in vec8_avx.h (avx, avx2), opmasks in
 * vec8_avx512vl.h (avx512vl8). The AVX2 and FMA forms sit beside their AVX
 * fallbacks, chosen by the compiler's flags, as in Embree's vfloat8_avx.h.
 * Semantics: see vec1_scalar.h. */
#ifndef LANES_SIMD_VEC8_YMM_H
#define LANES_SIMD_VEC8_YMM_H

#if !defined(__AVX__)
#error "vec8_ymm.h needs -mavx"
#endif

#include <stdbool.h>
#include <stdint.h>
#include <immintrin.h>

#include "vec4_sse4.h" /* the reductions end in its 4-lane ones: equal rounding at 4 and 8 */

typedef __m256 v8f;
typedef __m256i v8i;

static inline __m128i v8i_lo(v8i a) { return _mm256_castsi256_si128(a); }
static inline __m128i v8i_hi(v8i a) { return _mm256_extractf128_si256(a, 1); }
static inline v8i v8i_join(__m128i lo, __m128i hi)
{
    return _mm256_insertf128_si256(_mm256_castsi128_si256(lo), hi, 1);
}

/* Constructors */
static inline v8f v8f_zero(void) { return _mm256_setzero_ps(); }
static inline v8f v8f_set1(float x) { return _mm256_set1_ps(x); }
static inline v8i v8i_zero(void) { return _mm256_setzero_si256(); }
static inline v8i v8i_set1(int32_t x) { return _mm256_set1_epi32(x); }
static inline v8i v8i_iota(void) { return _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7); }

/* Load / store without a mask */
static inline v8f v8f_load(const float *p) { return _mm256_load_ps(p); }
static inline v8f v8f_loadu(const float *p) { return _mm256_loadu_ps(p); }
static inline void v8f_store(float *p, v8f v) { _mm256_store_ps(p, v); }
static inline void v8f_storeu(float *p, v8f v) { _mm256_storeu_ps(p, v); }
static inline v8i v8i_load(const int32_t *p) { return _mm256_load_si256((const __m256i *)p); }
static inline v8i v8i_loadu(const int32_t *p) { return _mm256_loadu_si256((const __m256i *)p); }
static inline void v8i_store(int32_t *p, v8i v) { _mm256_store_si256((__m256i *)p, v); }
static inline void v8i_storeu(int32_t *p, v8i v) { _mm256_storeu_si256((__m256i *)p, v); }
static inline v8f v8f_gather(const float *base, v8i idx)
{
#if defined(__AVX2__)
    return _mm256_i32gather_ps(base, idx, 4);
#else
    int32_t i[8];
    _mm256_storeu_si256((__m256i *)i, idx);
    return _mm256_setr_ps(base[i[0]], base[i[1]], base[i[2]], base[i[3]], base[i[4]],
                          base[i[5]], base[i[6]], base[i[7]]);
#endif
}
static inline v8i v8i_gather(const int32_t *base, v8i idx)
{
#if defined(__AVX2__)
    return _mm256_i32gather_epi32(base, idx, 4);
#else
    int32_t i[8];
    _mm256_storeu_si256((__m256i *)i, idx);
    return _mm256_setr_epi32(base[i[0]], base[i[1]], base[i[2]], base[i[3]], base[i[4]],
                             base[i[5]], base[i[6]], base[i[7]]);
#endif
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
#if defined(__FMA__)
static inline v8f v8f_fmadd(v8f a, v8f b, v8f c) { return _mm256_fmadd_ps(a, b, c); }
static inline v8f v8f_fmsub(v8f a, v8f b, v8f c) { return _mm256_fmsub_ps(a, b, c); }
static inline v8f v8f_fnmadd(v8f a, v8f b, v8f c) { return _mm256_fnmadd_ps(a, b, c); }
#else
static inline v8f v8f_fmadd(v8f a, v8f b, v8f c) { return _mm256_add_ps(_mm256_mul_ps(a, b), c); }
static inline v8f v8f_fmsub(v8f a, v8f b, v8f c) { return _mm256_sub_ps(_mm256_mul_ps(a, b), c); }
static inline v8f v8f_fnmadd(v8f a, v8f b, v8f c) { return _mm256_sub_ps(c, _mm256_mul_ps(a, b)); }
#endif
static inline v8f v8f_min(v8f a, v8f b) { return _mm256_min_ps(a, b); }
static inline v8f v8f_max(v8f a, v8f b) { return _mm256_max_ps(a, b); }
static inline v8f v8f_abs(v8f a)
{
    return _mm256_and_ps(a, _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff)));
}
static inline v8f v8f_neg(v8f a) { return _mm256_xor_ps(a, _mm256_set1_ps(-0.0f)); }
static inline v8f v8f_floor(v8f a) { return _mm256_floor_ps(a); }
static inline v8f v8f_sqrt(v8f a) { return _mm256_sqrt_ps(a); }
static inline v8f v8f_rcp(v8f a) { return _mm256_div_ps(_mm256_set1_ps(1.0f), a); }
#if defined(__AVX2__)
static inline v8i v8i_add(v8i a, v8i b) { return _mm256_add_epi32(a, b); }
static inline v8i v8i_sub(v8i a, v8i b) { return _mm256_sub_epi32(a, b); }
static inline v8i v8i_mul(v8i a, v8i b) { return _mm256_mullo_epi32(a, b); }
static inline v8i v8i_min(v8i a, v8i b) { return _mm256_min_epi32(a, b); }
static inline v8i v8i_max(v8i a, v8i b) { return _mm256_max_epi32(a, b); }
static inline v8i v8i_and(v8i a, v8i b) { return _mm256_and_si256(a, b); }
static inline v8i v8i_or(v8i a, v8i b) { return _mm256_or_si256(a, b); }
static inline v8i v8i_xor(v8i a, v8i b) { return _mm256_xor_si256(a, b); }
static inline v8i v8i_sll(v8i a, int n) { return _mm256_sll_epi32(a, _mm_cvtsi32_si128(n)); }
static inline v8i v8i_srl(v8i a, int n) { return _mm256_srl_epi32(a, _mm_cvtsi32_si128(n)); }
#else
#define LANES_V8I_HALVES(name, op)                                                          \
    static inline v8i name(v8i a, v8i b) { return v8i_join(op(v8i_lo(a), v8i_lo(b)), op(v8i_hi(a), v8i_hi(b))); }
LANES_V8I_HALVES(v8i_add, _mm_add_epi32)
LANES_V8I_HALVES(v8i_sub, _mm_sub_epi32)
LANES_V8I_HALVES(v8i_mul, _mm_mullo_epi32)
LANES_V8I_HALVES(v8i_min, _mm_min_epi32)
LANES_V8I_HALVES(v8i_max, _mm_max_epi32)
#undef LANES_V8I_HALVES
static inline v8i v8i_and(v8i a, v8i b)
{
    return _mm256_castps_si256(_mm256_and_ps(_mm256_castsi256_ps(a), _mm256_castsi256_ps(b)));
}
static inline v8i v8i_or(v8i a, v8i b)
{
    return _mm256_castps_si256(_mm256_or_ps(_mm256_castsi256_ps(a), _mm256_castsi256_ps(b)));
}
static inline v8i v8i_xor(v8i a, v8i b)
{
    return _mm256_castps_si256(_mm256_xor_ps(_mm256_castsi256_ps(a), _mm256_castsi256_ps(b)));
}
static inline v8i v8i_sll(v8i a, int n)
{
    __m128i c = _mm_cvtsi32_si128(n);
    return v8i_join(_mm_sll_epi32(v8i_lo(a), c), _mm_sll_epi32(v8i_hi(a), c));
}
static inline v8i v8i_srl(v8i a, int n)
{
    __m128i c = _mm_cvtsi32_si128(n);
    return v8i_join(_mm_srl_epi32(v8i_lo(a), c), _mm_srl_epi32(v8i_hi(a), c));
}
#endif

/* Conversions */
static inline v8i v8f_as_vi(v8f a) { return _mm256_castps_si256(a); }
static inline v8f v8i_as_vf(v8i a) { return _mm256_castsi256_ps(a); }
static inline v8f v8i_to_vf(v8i a) { return _mm256_cvtepi32_ps(a); }
static inline v8i v8f_to_vi(v8f a) { return _mm256_cvttps_epi32(a); }

/* Reductions (NaN-free input) */
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
