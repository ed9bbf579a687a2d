/* 16 lanes from two AVX2 halves: the avx512emu set. Same operations and the
 * same mask semantics as the native 16-lane set, so 16-wide kernels run on
 * any AVX2 CPU. Masks stay two 8-lane vector masks (as ISPC's avx2-i32x16
 * keeps them): converting to 16-bit masks on every operation is what makes
 * emulation layers slow. Only v16m_bits() produces bits.
 * Semantics: see vec1_scalar.h. */
#ifndef LANES_SIMD_VEC16_AVX512EMU_H
#define LANES_SIMD_VEC16_AVX512EMU_H

#include "vec8_avx.h"

#if !defined(__AVX2__) || !defined(__FMA__)
#error "avx512emu is built on AVX2 and FMA"
#endif

typedef struct { v8f lo, hi; } v16f;
typedef struct { v8i lo, hi; } v16i;
typedef struct { v8m lo, hi; } v16m;

#define LANES_V16_UNARY(T, name, op8)  static inline T name(T a) { return (T){op8(a.lo), op8(a.hi)}; }
#define LANES_V16_BINARY(T, R, name, op8)                                                   \
    static inline R name(T a, T b) { return (R){op8(a.lo, b.lo), op8(a.hi, b.hi)}; }
#define LANES_V16_TERNARY(T, name, op8)                                                     \
    static inline T name(T a, T b, T c) { return (T){op8(a.lo, b.lo, c.lo), op8(a.hi, b.hi, c.hi)}; }

/* Constructors */
static inline v16f v16f_zero(void) { return (v16f){v8f_zero(), v8f_zero()}; }
static inline v16f v16f_set1(float x) { return (v16f){v8f_set1(x), v8f_set1(x)}; }
static inline v16i v16i_zero(void) { return (v16i){v8i_zero(), v8i_zero()}; }
static inline v16i v16i_set1(int32_t x) { return (v16i){v8i_set1(x), v8i_set1(x)}; }
static inline v16i v16i_iota(void) { return (v16i){v8i_iota(), v8i_add(v8i_iota(), v8i_set1(8))}; }
static inline v16m v16m_true(void) { return (v16m){v8m_true(), v8m_true()}; }
static inline v16m v16m_false(void) { return (v16m){v8m_false(), v8m_false()}; }
static inline v16m v16m_first_n(size_t n)
{
    return (v16m){v8m_first_n(n), v8m_first_n(n > 8 ? n - 8 : 0)};
}
static inline v16m v16m_from_bits(uint32_t bits)
{
    return (v16m){v8m_from_bits(bits & 0xffu), v8m_from_bits((bits >> 8) & 0xffu)};
}
static inline uint32_t v16m_bits(v16m a) { return v8m_bits(a.lo) | (v8m_bits(a.hi) << 8); }

/* Load / store */
static inline v16f v16f_load(const float *p) { return (v16f){v8f_load(p), v8f_load(p + 8)}; }
static inline v16f v16f_loadu(const float *p) { return (v16f){v8f_loadu(p), v8f_loadu(p + 8)}; }
static inline v16f v16f_load_masked(v16m m, const float *p)
{
    return (v16f){v8f_load_masked(m.lo, p), v8f_load_masked(m.hi, p + 8)};
}
static inline void v16f_store(float *p, v16f v) { v8f_store(p, v.lo); v8f_store(p + 8, v.hi); }
static inline void v16f_storeu(float *p, v16f v) { v8f_storeu(p, v.lo); v8f_storeu(p + 8, v.hi); }
static inline void v16f_store_masked(float *p, v16m m, v16f v)
{
    v8f_store_masked(p, m.lo, v.lo);
    v8f_store_masked(p + 8, m.hi, v.hi);
}
static inline v16i v16i_load(const int32_t *p) { return (v16i){v8i_load(p), v8i_load(p + 8)}; }
static inline v16i v16i_loadu(const int32_t *p) { return (v16i){v8i_loadu(p), v8i_loadu(p + 8)}; }
static inline void v16i_store(int32_t *p, v16i v) { v8i_store(p, v.lo); v8i_store(p + 8, v.hi); }
static inline void v16i_storeu(int32_t *p, v16i v) { v8i_storeu(p, v.lo); v8i_storeu(p + 8, v.hi); }
static inline void v16i_store_masked(int32_t *p, v16m m, v16i v)
{
    v8i_store_masked(p, m.lo, v.lo);
    v8i_store_masked(p + 8, m.hi, v.hi);
}
static inline void v16f_store_merge(float *p, v16m m, v16f v)
{
    v8f_store_merge(p, m.lo, v.lo);
    v8f_store_merge(p + 8, m.hi, v.hi);
}
static inline void v16i_store_merge(int32_t *p, v16m m, v16i v)
{
    v8i_store_merge(p, m.lo, v.lo);
    v8i_store_merge(p + 8, m.hi, v.hi);
}
static inline v16f v16f_gather(const float *base, v16i idx)
{
    return (v16f){v8f_gather(base, idx.lo), v8f_gather(base, idx.hi)};
}
static inline v16i v16i_gather(const int32_t *base, v16i idx)
{
    return (v16i){v8i_gather(base, idx.lo), v8i_gather(base, idx.hi)};
}
static inline int v16i_compress_store(int32_t *dst, v16m m, v16i v)
{
    int n = v8i_compress_store(dst, m.lo, v.lo);
    return n + v8i_compress_store(dst + n, m.hi, v.hi);
}
static inline int v16f_compress_store(float *dst, v16m m, v16f v)
{
    int n = v8f_compress_store(dst, m.lo, v.lo);
    return n + v8f_compress_store(dst + n, m.hi, v.hi);
}
static inline float v16f_lane(v16f v, int i) { return i < 8 ? v8f_lane(v.lo, i) : v8f_lane(v.hi, i - 8); }
static inline int32_t v16i_lane(v16i v, int i) { return i < 8 ? v8i_lane(v.lo, i) : v8i_lane(v.hi, i - 8); }

/* Arithmetic */
LANES_V16_BINARY(v16f, v16f, v16f_add, v8f_add)
LANES_V16_BINARY(v16f, v16f, v16f_sub, v8f_sub)
LANES_V16_BINARY(v16f, v16f, v16f_mul, v8f_mul)
LANES_V16_BINARY(v16f, v16f, v16f_div, v8f_div)
LANES_V16_TERNARY(v16f, v16f_fmadd, v8f_fmadd)
LANES_V16_TERNARY(v16f, v16f_fmsub, v8f_fmsub)
LANES_V16_TERNARY(v16f, v16f_fnmadd, v8f_fnmadd)
LANES_V16_BINARY(v16f, v16f, v16f_min, v8f_min)
LANES_V16_BINARY(v16f, v16f, v16f_max, v8f_max)
LANES_V16_UNARY(v16f, v16f_abs, v8f_abs)
LANES_V16_UNARY(v16f, v16f_neg, v8f_neg)
LANES_V16_UNARY(v16f, v16f_floor, v8f_floor)
LANES_V16_UNARY(v16f, v16f_sqrt, v8f_sqrt)
LANES_V16_UNARY(v16f, v16f_rcp, v8f_rcp)
LANES_V16_UNARY(v16f, v16f_rcp_fast, v8f_rcp_fast)
LANES_V16_UNARY(v16f, v16f_rcp_nr, v8f_rcp_nr)
LANES_V16_BINARY(v16i, v16i, v16i_add, v8i_add)
LANES_V16_BINARY(v16i, v16i, v16i_sub, v8i_sub)
LANES_V16_BINARY(v16i, v16i, v16i_mul, v8i_mul)
LANES_V16_BINARY(v16i, v16i, v16i_and, v8i_and)
LANES_V16_BINARY(v16i, v16i, v16i_or, v8i_or)
LANES_V16_BINARY(v16i, v16i, v16i_xor, v8i_xor)
LANES_V16_BINARY(v16i, v16i, v16i_min, v8i_min)
LANES_V16_BINARY(v16i, v16i, v16i_max, v8i_max)
static inline v16i v16i_sll(v16i a, int n) { return (v16i){v8i_sll(a.lo, n), v8i_sll(a.hi, n)}; }
static inline v16i v16i_srl(v16i a, int n) { return (v16i){v8i_srl(a.lo, n), v8i_srl(a.hi, n)}; }

/* Conversions */
static inline v16i v16f_as_vi(v16f a) { return (v16i){v8f_as_vi(a.lo), v8f_as_vi(a.hi)}; }
static inline v16f v16i_as_vf(v16i a) { return (v16f){v8i_as_vf(a.lo), v8i_as_vf(a.hi)}; }
static inline v16f v16i_to_vf(v16i a) { return (v16f){v8i_to_vf(a.lo), v8i_to_vf(a.hi)}; }
static inline v16i v16f_to_vi(v16f a) { return (v16i){v8f_to_vi(a.lo), v8f_to_vi(a.hi)}; }

/* Compare / mask */
LANES_V16_BINARY(v16f, v16m, v16f_lt, v8f_lt)
LANES_V16_BINARY(v16f, v16m, v16f_le, v8f_le)
LANES_V16_BINARY(v16f, v16m, v16f_gt, v8f_gt)
LANES_V16_BINARY(v16f, v16m, v16f_ge, v8f_ge)
LANES_V16_BINARY(v16f, v16m, v16f_eq, v8f_eq)
LANES_V16_BINARY(v16f, v16m, v16f_neq, v8f_neq)
LANES_V16_UNARY(v16m, v16m_not, v8m_not)
static inline v16m v16f_isnan(v16f a) { return (v16m){v8f_isnan(a.lo), v8f_isnan(a.hi)}; }
LANES_V16_BINARY(v16i, v16m, v16i_eq, v8i_eq)
LANES_V16_BINARY(v16i, v16m, v16i_lt, v8i_lt)
LANES_V16_BINARY(v16i, v16m, v16i_gt, v8i_gt)
LANES_V16_BINARY(v16m, v16m, v16m_and, v8m_and)
LANES_V16_BINARY(v16m, v16m, v16m_or, v8m_or)
LANES_V16_BINARY(v16m, v16m, v16m_andnot, v8m_andnot)
LANES_V16_BINARY(v16m, v16m, v16m_xor, v8m_xor)
static inline bool v16m_any(v16m a) { return v8m_any(_mm256_or_ps(a.lo, a.hi)); }
static inline bool v16m_none(v16m a) { return v8m_none(_mm256_or_ps(a.lo, a.hi)); }
static inline bool v16m_all(v16m a) { return v8m_all(_mm256_and_ps(a.lo, a.hi)); }
static inline int v16m_popcount(v16m a) { return _mm_popcnt_u32(v16m_bits(a)); }

/* Select: m ? a : b */
static inline v16f v16f_select(v16m m, v16f a, v16f b)
{
    return (v16f){v8f_select(m.lo, a.lo, b.lo), v8f_select(m.hi, a.hi, b.hi)};
}
static inline v16i v16i_select(v16m m, v16i a, v16i b)
{
    return (v16i){v8i_select(m.lo, a.lo, b.lo), v8i_select(m.hi, a.hi, b.hi)};
}

/* Reductions (NaN-free input) */
static inline float v16f_reduce_min(v16f a) { return v8f_reduce_min(v8f_min(a.lo, a.hi)); }
static inline float v16f_reduce_max(v16f a) { return v8f_reduce_max(v8f_max(a.lo, a.hi)); }
static inline float v16f_reduce_add(v16f a) { return v8f_reduce_add(v8f_add(a.lo, a.hi)); }

#undef LANES_V16_UNARY
#undef LANES_V16_BINARY
#undef LANES_V16_TERNARY

#endif
