/* The width-generic face of the SIMD layer. A per-ISA source file is
 * compiled once per kernel set with LANES_KSET_<SET> defined (cmake/LanesIsa.cmake
 * does it); this header then maps the generic names onto that set's backend:
 *
 *   vfloat, vint, vmask   vectors of LANES_W floats, int32s and lane masks
 *   vf_*, vi_*, vm_*      operations (the list below; semantics in vec1_scalar.h)
 *   LANES_FN(name)        name with the set's suffix: name_avx2, ...
 *
 * A kernel written against these names is written once and runs at every
 * width. Everything the backends define is static inline, so no copy of an
 * AVX-512 helper can be merged by the linker into code for another set. */
#ifndef LANES_SIMD_SIMD_H
#define LANES_SIMD_SIMD_H

#define LANES_CAT_(a, b) a##b
#define LANES_CAT(a, b) LANES_CAT_(a, b)

#if defined(LANES_KSET_SCALAR)
#include "vec1_scalar.h"
#define LANES_W 1
#define LANES_VPREFIX v1
#define LANES_SUFFIX _scalar
#define LANES_KSET_NAME "scalar"
#define LANES_THIS_ISA LANES_ISA_SCALAR
#elif defined(LANES_KSET_SSE4)
#if !defined(__SSE4_1__) || !defined(__POPCNT__)
#error "the sse4 set needs -msse4.1 -mpopcnt"
#endif
#include "vec4_sse4.h"
#define LANES_W 4
#define LANES_VPREFIX v4
#define LANES_SUFFIX _sse4
#define LANES_KSET_NAME "sse4"
#define LANES_THIS_ISA LANES_ISA_SSE4
#elif defined(LANES_KSET_AVX)
#if !defined(__AVX__) || defined(__AVX2__) || defined(__FMA__)
#error "the avx set needs -mavx and neither AVX2 nor FMA"
#endif
#include "vec8_avx.h"
#define LANES_W 8
#define LANES_VPREFIX v8
#define LANES_SUFFIX _avx
#define LANES_KSET_NAME "avx"
#define LANES_THIS_ISA LANES_ISA_AVX
#elif defined(LANES_KSET_AVX2)
#if !defined(__AVX2__) || !defined(__FMA__) || defined(__AVX512F__)
#error "the avx2 set needs -mavx2 -mfma and no AVX-512"
#endif
#include "vec8_avx.h"
#define LANES_W 8
#define LANES_VPREFIX v8
#define LANES_SUFFIX _avx2
#define LANES_KSET_NAME "avx2"
#define LANES_THIS_ISA LANES_ISA_AVX2
#elif defined(LANES_KSET_AVX512EMU)
#if !defined(__AVX2__) || !defined(__FMA__) || defined(__AVX512F__)
#error "the avx512emu set needs -mavx2 -mfma and no AVX-512"
#endif
#include "vec16_avx512emu.h"
#define LANES_W 16
#define LANES_VPREFIX v16
#define LANES_SUFFIX _avx512emu
#define LANES_KSET_NAME "avx512emu"
#define LANES_THIS_ISA LANES_ISA_AVX512EMU
#elif defined(LANES_KSET_AVX512)
#if !defined(__AVX512F__) || !defined(__AVX512DQ__) || !defined(__AVX512BW__) || !defined(__AVX512VL__)
#error "the avx512 set needs -mavx512f -mavx512dq -mavx512bw -mavx512vl"
#endif
#include "vec16_avx512.h"
#define LANES_W 16
#define LANES_VPREFIX v16
#define LANES_SUFFIX _avx512
#define LANES_KSET_NAME "avx512"
#define LANES_THIS_ISA LANES_ISA_AVX512
#else
#error "compile per-ISA sources with one LANES_KSET_<SET> defined"
#endif

#define LANES_FN(name) LANES_CAT(name, LANES_SUFFIX)
#define LANES_VOP(op) LANES_CAT(LANES_VPREFIX, op)

typedef LANES_CAT(LANES_VPREFIX, f) vfloat;
typedef LANES_CAT(LANES_VPREFIX, i) vint;
typedef LANES_CAT(LANES_VPREFIX, m) vmask;

#define vf_zero LANES_VOP(f_zero)
#define vf_set1 LANES_VOP(f_set1)
#define vf_load LANES_VOP(f_load)
#define vf_loadu LANES_VOP(f_loadu)
#define vf_load_masked LANES_VOP(f_load_masked)
#define vf_store LANES_VOP(f_store)
#define vf_storeu LANES_VOP(f_storeu)
#define vf_store_masked LANES_VOP(f_store_masked)
#define vf_gather LANES_VOP(f_gather)
#define vf_compress_store LANES_VOP(f_compress_store)
#define vf_lane LANES_VOP(f_lane)
#define vf_add LANES_VOP(f_add)
#define vf_sub LANES_VOP(f_sub)
#define vf_mul LANES_VOP(f_mul)
#define vf_div LANES_VOP(f_div)
#define vf_fmadd LANES_VOP(f_fmadd)
#define vf_fmsub LANES_VOP(f_fmsub)
#define vf_fnmadd LANES_VOP(f_fnmadd)
#define vf_min LANES_VOP(f_min)
#define vf_max LANES_VOP(f_max)
#define vf_abs LANES_VOP(f_abs)
#define vf_neg LANES_VOP(f_neg)
#define vf_sqrt LANES_VOP(f_sqrt)
#define vf_rcp LANES_VOP(f_rcp)
#define vf_rcp_fast LANES_VOP(f_rcp_fast)
#define vf_rcp_nr LANES_VOP(f_rcp_nr)
#define vf_as_vi LANES_VOP(f_as_vi)
#define vf_to_vi LANES_VOP(f_to_vi)
#define vf_lt LANES_VOP(f_lt)
#define vf_le LANES_VOP(f_le)
#define vf_gt LANES_VOP(f_gt)
#define vf_ge LANES_VOP(f_ge)
#define vf_eq LANES_VOP(f_eq)
#define vf_neq LANES_VOP(f_neq)
#define vf_isnan LANES_VOP(f_isnan)
#define vf_select LANES_VOP(f_select)
#define vf_reduce_min LANES_VOP(f_reduce_min)
#define vf_reduce_max LANES_VOP(f_reduce_max)
#define vf_reduce_add LANES_VOP(f_reduce_add)
#define vi_zero LANES_VOP(i_zero)
#define vi_set1 LANES_VOP(i_set1)
#define vi_iota LANES_VOP(i_iota)
#define vi_load LANES_VOP(i_load)
#define vi_loadu LANES_VOP(i_loadu)
#define vi_store LANES_VOP(i_store)
#define vi_storeu LANES_VOP(i_storeu)
#define vi_store_masked LANES_VOP(i_store_masked)
#define vi_gather LANES_VOP(i_gather)
#define vi_compress_store LANES_VOP(i_compress_store)
#define vi_lane LANES_VOP(i_lane)
#define vi_add LANES_VOP(i_add)
#define vi_sub LANES_VOP(i_sub)
#define vi_and LANES_VOP(i_and)
#define vi_or LANES_VOP(i_or)
#define vi_xor LANES_VOP(i_xor)
#define vi_sll LANES_VOP(i_sll)
#define vi_srl LANES_VOP(i_srl)
#define vi_min LANES_VOP(i_min)
#define vi_max LANES_VOP(i_max)
#define vi_as_vf LANES_VOP(i_as_vf)
#define vi_to_vf LANES_VOP(i_to_vf)
#define vi_eq LANES_VOP(i_eq)
#define vi_lt LANES_VOP(i_lt)
#define vi_gt LANES_VOP(i_gt)
#define vi_select LANES_VOP(i_select)
#define vm_true LANES_VOP(m_true)
#define vm_false LANES_VOP(m_false)
#define vm_first_n LANES_VOP(m_first_n)
#define vm_from_bits LANES_VOP(m_from_bits)
#define vm_bits LANES_VOP(m_bits)
#define vm_and LANES_VOP(m_and)
#define vm_or LANES_VOP(m_or)
#define vm_andnot LANES_VOP(m_andnot)
#define vm_xor LANES_VOP(m_xor)
#define vm_not LANES_VOP(m_not)
#define vm_any LANES_VOP(m_any)
#define vm_all LANES_VOP(m_all)
#define vm_none LANES_VOP(m_none)
#define vm_popcount LANES_VOP(m_popcount)

/* What the compiler was told it may use, for the hygiene tests. */
#define LANES_COMPILED_FEATURES                                                           \
    (LANES_HAS_SSE41_ | LANES_HAS_AVX_ | LANES_HAS_AVX2_ | LANES_HAS_FMA_ | LANES_HAS_AVX512F_)
#ifdef __SSE4_1__
#define LANES_HAS_SSE41_ 1u
#else
#define LANES_HAS_SSE41_ 0u
#endif
#ifdef __AVX__
#define LANES_HAS_AVX_ 2u
#else
#define LANES_HAS_AVX_ 0u
#endif
#ifdef __AVX2__
#define LANES_HAS_AVX2_ 4u
#else
#define LANES_HAS_AVX2_ 0u
#endif
#ifdef __FMA__
#define LANES_HAS_FMA_ 8u
#else
#define LANES_HAS_FMA_ 0u
#endif
#ifdef __AVX512F__
#define LANES_HAS_AVX512F_ 16u
#else
#define LANES_HAS_AVX512F_ 0u
#endif

#endif
