/* 8 lanes with vector masks: the avx set (AVX, no AVX2, no FMA: Sandy Bridge,
 * Ivy Bridge) and the avx2 set (AVX2 + FMA), one header, the AVX2 forms
 * beside their AVX fallbacks as in Embree's vfloat8_avx.h. Which one a file
 * gets is decided by the compiler's flags (__AVX2__, __FMA__), that is by the
 * set being built. What does not take a mask is in vec8_ymm.h, shared with
 * avx512vl8.
 * - AVX has no 256-bit integer instructions: integer operations work on two
 *   SSE halves, gathers are scalar loads, compress stores go per 128-bit half.
 * - Without FMA, fmadd is a multiply and an add, rounded twice.
 * Semantics: see vec1_scalar.h. */
#ifndef LANES_SIMD_VEC8_AVX_H
#define LANES_SIMD_VEC8_AVX_H

#if !defined(__AVX__)
#error "vec8_avx.h needs -mavx (and, for the avx2 set, -mavx2 -mfma)"
#endif

#include "vec8_ymm.h"

typedef __m256 v8m; /* all ones or all zeros per lane */

/* Masks */
static inline v8m v8m_true(void) { return _mm256_castsi256_ps(_mm256_set1_epi32(-1)); }
static inline v8m v8m_false(void) { return _mm256_setzero_ps(); }
static inline v8m v8m_first_n(size_t n)
{
    float k = n > 8 ? 8.0f : (float)n;
    return _mm256_cmp_ps(_mm256_setr_ps(0, 1, 2, 3, 4, 5, 6, 7), _mm256_set1_ps(k), _CMP_LT_OQ);
}
static inline v8m v8m_from_bits(uint32_t bits)
{
    __m128i b = _mm_set1_epi32((int32_t)bits);
    __m128i sel_lo = _mm_setr_epi32(1, 2, 4, 8), sel_hi = _mm_setr_epi32(16, 32, 64, 128);
    __m128i lo = _mm_cmpeq_epi32(_mm_and_si128(b, sel_lo), sel_lo);
    __m128i hi = _mm_cmpeq_epi32(_mm_and_si128(b, sel_hi), sel_hi);
    return _mm256_castsi256_ps(v8i_join(lo, hi));
}
static inline uint32_t v8m_bits(v8m a) { return (uint32_t)_mm256_movemask_ps(a); }

/* Masked load / store, compress */
static inline v8f v8f_load_masked(v8m m, const float *p)
{
    return _mm256_maskload_ps(p, _mm256_castps_si256(m));
}
static inline void v8f_store_masked(float *p, v8m m, v8f v)
{
    _mm256_maskstore_ps(p, _mm256_castps_si256(m), v);
}
static inline void v8i_store_masked(int32_t *p, v8m m, v8i v)
{
    _mm256_maskstore_ps((float *)(void *)p, _mm256_castps_si256(m), _mm256_castsi256_ps(v));
}
/* A masked store (VMASKMOVPS to memory) took 11-19 cycles on a Zen 3,
 * measured, against 1.5-4 for a load, a blend and a store of all eight
 * elements; the box and triangle rows of lanes bench kernels ran 1.6-3x
 * faster for it there. Not measured on Intel cores, where the masked store
 * is documented as cheap. */
static inline void v8f_store_merge(float *p, v8m m, v8f v)
{
    _mm256_storeu_ps(p, _mm256_blendv_ps(_mm256_loadu_ps(p), v, m));
}
static inline void v8i_store_merge(int32_t *p, v8m m, v8i v)
{
    __m256 old = _mm256_loadu_ps((const float *)(const void *)p);
    _mm256_storeu_ps((float *)(void *)p, _mm256_blendv_ps(old, _mm256_castsi256_ps(v), m));
}
static inline int v8i_compress_store(int32_t *dst, v8m m, v8i v)
{
#if defined(__AVX2__)
    /* Nibble i of lane_order[b] is the i-th set lane of the 4-bit mask b;
     * the high half's lanes are 4..7 and follow the low half's. */
    static const uint32_t lane_order[16] = {0x0,  0x0,   0x1,   0x10,  0x2,   0x20,  0x21,  0x210,
                                            0x3,  0x30,  0x31,  0x310, 0x32,  0x320, 0x321, 0x3210};
    uint32_t bits = v8m_bits(m);
    int n_lo = _mm_popcnt_u32(bits & 15u), n = _mm_popcnt_u32(bits);
    uint32_t order = lane_order[bits & 15u] | ((lane_order[bits >> 4] + 0x4444u) << (4 * n_lo));
    __m256i perm = _mm256_and_si256(_mm256_srlv_epi32(_mm256_set1_epi32((int32_t)order),
                                                      _mm256_setr_epi32(0, 4, 8, 12, 16, 20, 24, 28)),
                                    _mm256_set1_epi32(7));
    __m256i packed = _mm256_permutevar8x32_epi32(v, perm);
    _mm256_maskstore_epi32(dst, _mm256_castps_si256(v8m_first_n((size_t)n)), packed);
    return n;
#else
    int n_lo = v4i_compress_store(dst, _mm256_castps256_ps128(m), v8i_lo(v));
    int n_hi = v4i_compress_store(dst + n_lo, _mm256_extractf128_ps(m, 1), v8i_hi(v));
    return n_lo + n_hi;
#endif
}
static inline int v8f_compress_store(float *dst, v8m m, v8f v)
{
    return v8i_compress_store((int32_t *)(void *)dst, m, _mm256_castps_si256(v));
}

/* The fast reciprocal: RCPPS, about 12 bits */
static inline v8f v8f_rcp_fast(v8f a) { return _mm256_rcp_ps(a); }
static inline v8f v8f_rcp_nr(v8f a)
{
    v8f r = _mm256_rcp_ps(a);
    return v8f_fmadd(r, v8f_fnmadd(a, r, _mm256_set1_ps(1.0f)), r);
}

/* Compare / mask */
static inline v8m v8f_lt(v8f a, v8f b) { return _mm256_cmp_ps(a, b, _CMP_LT_OQ); }
static inline v8m v8f_le(v8f a, v8f b) { return _mm256_cmp_ps(a, b, _CMP_LE_OQ); }
static inline v8m v8f_gt(v8f a, v8f b) { return _mm256_cmp_ps(a, b, _CMP_GT_OQ); }
static inline v8m v8f_ge(v8f a, v8f b) { return _mm256_cmp_ps(a, b, _CMP_GE_OQ); }
static inline v8m v8f_eq(v8f a, v8f b) { return _mm256_cmp_ps(a, b, _CMP_EQ_OQ); }
static inline v8m v8f_neq(v8f a, v8f b) { return _mm256_cmp_ps(a, b, _CMP_NEQ_UQ); }
static inline v8m v8f_isnan(v8f a) { return _mm256_cmp_ps(a, a, _CMP_UNORD_Q); }
#if defined(__AVX2__)
static inline v8m v8i_eq(v8i a, v8i b) { return _mm256_castsi256_ps(_mm256_cmpeq_epi32(a, b)); }
static inline v8m v8i_lt(v8i a, v8i b) { return _mm256_castsi256_ps(_mm256_cmpgt_epi32(b, a)); }
static inline v8m v8i_gt(v8i a, v8i b) { return _mm256_castsi256_ps(_mm256_cmpgt_epi32(a, b)); }
#else
#define LANES_V8I_CMP(name, op)                                                             \
    static inline v8m name(v8i a, v8i b)                                                    \
    {                                                                                       \
        return _mm256_castsi256_ps(v8i_join(op(v8i_lo(a), v8i_lo(b)), op(v8i_hi(a), v8i_hi(b)))); \
    }
LANES_V8I_CMP(v8i_eq, _mm_cmpeq_epi32)
LANES_V8I_CMP(v8i_lt, _mm_cmplt_epi32)
LANES_V8I_CMP(v8i_gt, _mm_cmpgt_epi32)
#undef LANES_V8I_CMP
#endif
static inline v8m v8m_and(v8m a, v8m b) { return _mm256_and_ps(a, b); }
static inline v8m v8m_or(v8m a, v8m b) { return _mm256_or_ps(a, b); }
static inline v8m v8m_andnot(v8m a, v8m b) { return _mm256_andnot_ps(b, a); }
static inline v8m v8m_xor(v8m a, v8m b) { return _mm256_xor_ps(a, b); }
static inline v8m v8m_not(v8m a) { return _mm256_xor_ps(a, v8m_true()); }
static inline bool v8m_any(v8m a) { return !_mm256_testz_ps(a, a); }
static inline bool v8m_all(v8m a) { return _mm256_movemask_ps(a) == 0xff; }
static inline bool v8m_none(v8m a) { return _mm256_testz_ps(a, a); }
static inline int v8m_popcount(v8m a) { return _mm_popcnt_u32(v8m_bits(a)); }

/* Select: m ? a : b. Without AVX2, GCC 12 rewrites BLENDVPS on a compare
 * mask into a per-lane select it cannot express in 256-bit integer code
 * and emits a branch per lane (measured: 3.7x the instructions of the AVX2
 * build in the box kernel). The and/andnot/or form has no such trap. */
#if defined(__AVX2__)
static inline v8f v8f_select(v8m m, v8f a, v8f b) { return _mm256_blendv_ps(b, a, m); }
#else
static inline v8f v8f_select(v8m m, v8f a, v8f b)
{
    return _mm256_or_ps(_mm256_and_ps(m, a), _mm256_andnot_ps(m, b));
}
#endif
static inline v8i v8i_select(v8m m, v8i a, v8i b)
{
    return _mm256_castps_si256(v8f_select(m, _mm256_castsi256_ps(a), _mm256_castsi256_ps(b)));
}

#endif
