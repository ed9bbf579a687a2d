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

#define LANES_STR_(a) #a
#define LANES_STR(a) LANES_STR_(a)

/* lanes_add_kernel_sets (cmake/LanesIsa.cmake) defines, from the set's row
 * in kernel_sets.h and its CMake flags: LANES_KSET_ID (AVX2),
 * LANES_KSET_TOKEN (avx2), LANES_KSET_LANES (8) and LANES_KSET_HEADER (the
 * backend, "vec8_avx.h"). Each backend checks that the compiler flags give
 * it what it needs. */
#if !defined(LANES_KSET_ID) || !defined(LANES_KSET_TOKEN) || !defined(LANES_KSET_LANES) ||   \
    !defined(LANES_KSET_HEADER)
#error "compile per-ISA sources with lanes_add_kernel_sets (cmake/LanesIsa.cmake)"
#endif
#include LANES_KSET_HEADER
#define LANES_W LANES_KSET_LANES
#define LANES_VPREFIX LANES_CAT(v, LANES_KSET_LANES)
#define LANES_SUFFIX LANES_CAT(_, LANES_KSET_TOKEN)
#define LANES_KSET_NAME LANES_STR(LANES_KSET_TOKEN)
#define LANES_THIS_ISA LANES_CAT(LANES_ISA_, LANES_KSET_ID)

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
#define vf_store_merge LANES_VOP(f_store_merge)
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
#define vf_floor LANES_VOP(f_floor)
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
#define vi_store_merge LANES_VOP(i_store_merge)
#define vi_gather LANES_VOP(i_gather)
#define vi_compress_store LANES_VOP(i_compress_store)
#define vi_lane LANES_VOP(i_lane)
#define vi_add LANES_VOP(i_add)
#define vi_sub LANES_VOP(i_sub)
#define vi_mul LANES_VOP(i_mul)
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
