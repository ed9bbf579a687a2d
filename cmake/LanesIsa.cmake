# One source, many widths: the per-ISA kernel sources are compiled once per
# kernel set, each as its own OBJECT library with that set's flags and a
# LANES_KSET_<SET> definition (simd/simd.h turns it into the symbol suffix).
# Installed with the CMake package (find_package(lanes) includes it), so
# other projects build their own width-generic kernels the same way.
#
# Flags go on each target with target_compile_options: source-file
# properties are per directory and would leak one set's flags into all.

include(CheckCSourceCompiles)

set(LANES_ALL_ISAS scalar sse4 avx avx2 avx512emu avx512)

set(LANES_ISA_FLAGS_scalar "")
set(LANES_ISA_FLAGS_sse4 -msse4.1 -mpopcnt)
set(LANES_ISA_FLAGS_avx -mavx -mpopcnt)
set(LANES_ISA_FLAGS_avx2 -mavx2 -mfma -mpopcnt)
set(LANES_ISA_FLAGS_avx512emu -mavx2 -mfma -mpopcnt)
set(LANES_ISA_FLAGS_avx512 -mavx2 -mfma -mpopcnt -mavx512f -mavx512dq -mavx512bw -mavx512vl)

# A program using one characteristic instruction of the set. It must compile,
# assemble and link: a compiler can accept a flag whose instructions its
# assembler does not know.
set(LANES_ISA_PROBE_scalar "int main(void) { return 0; }")
set(LANES_ISA_PROBE_sse4 "#include <smmintrin.h>
#include <nmmintrin.h>
int main(void) { __m128 a = _mm_set1_ps(1.0f); a = _mm_blendv_ps(a, a, a);
  return _mm_popcnt_u32((unsigned)_mm_movemask_ps(a)); }")
set(LANES_ISA_PROBE_avx "#include <immintrin.h>
int main(void) { __m256 a = _mm256_set1_ps(1.0f); a = _mm256_blendv_ps(a, a, a);
  return _mm256_movemask_ps(a); }")
set(LANES_ISA_PROBE_avx2 "#include <immintrin.h>
int main(void) { __m256 a = _mm256_fmadd_ps(_mm256_set1_ps(1.0f), _mm256_set1_ps(2.0f), _mm256_set1_ps(3.0f));
  __m256i p = _mm256_permutevar8x32_epi32(_mm256_castps_si256(a), _mm256_set1_epi32(1));
  return _mm256_movemask_ps(_mm256_castsi256_ps(p)); }")
set(LANES_ISA_PROBE_avx512emu "${LANES_ISA_PROBE_avx2}")
set(LANES_ISA_PROBE_avx512 "#include <immintrin.h>
int main(void) { __m512 a = _mm512_set1_ps(1.0f);
  __m512 c = _mm512_maskz_compress_ps((__mmask16)0x5555, a);
  __m256 y = _mm256_mask_blend_ps((__mmask8)3, _mm256_setzero_ps(), _mm256_set1_ps(1.0f));
  return (int)_mm512_cmp_ps_mask(c, a, _CMP_EQ_OQ) + _mm256_movemask_ps(y); }")

# lanes_probe_isa(<set> <result-var>)
function(lanes_probe_isa isa out)
  set(CMAKE_REQUIRED_FLAGS "")
  string(REPLACE ";" " " flags "${LANES_ISA_FLAGS_${isa}}")
  set(CMAKE_REQUIRED_FLAGS "${flags}")
  set(CMAKE_REQUIRED_QUIET ON)
  check_c_source_compiles("${LANES_ISA_PROBE_${isa}}" LANES_PROBE_OK_${isa})
  set(${out} ${LANES_PROBE_OK_${isa}} PARENT_SCOPE)
endfunction()

# lanes_add_kernel_sets(<target-prefix> SOURCES <files...> SETS <sets...>
#                       [LINK <targets...>])
# Creates <prefix>_<set> OBJECT libraries, one per set, each compiled with
# that set's flags, LANES_KSET_<SET> and -ffp-contract=off (FMA only where
# the code says vf_fmadd), and linked to LINK (default lanes::simd, the SIMD
# layer's headers). Sets in the caller's scope:
#   LANES_KERNEL_OBJECTS      their objects, to add to a library or program
#   LANES_KERNEL_DEFINITIONS  LANES_HAVE_KSET_<SET> for each set, for the
#                             baseline file that dispatches between them
function(lanes_add_kernel_sets prefix)
  cmake_parse_arguments(ARG "" "" "SOURCES;SETS;LINK" ${ARGN})
  if(NOT ARG_LINK)
    set(ARG_LINK lanes::simd)
  endif()
  set(objects "")
  set(definitions "")
  foreach(isa IN LISTS ARG_SETS)
    if(NOT DEFINED LANES_ISA_FLAGS_${isa})
      message(FATAL_ERROR "lanes_add_kernel_sets: unknown kernel set '${isa}' (${LANES_ALL_ISAS})")
    endif()
    string(TOUPPER "${isa}" ISA)
    set(target ${prefix}_${isa})
    add_library(${target} OBJECT ${ARG_SOURCES})
    target_compile_definitions(${target} PRIVATE LANES_KSET_${ISA})
    target_compile_options(${target} PRIVATE ${LANES_ISA_FLAGS_${isa}} -ffp-contract=off
      # kernels run only what they say: no auto-vectoriser in the way of the
      # measured utilisation, and never into baseline code through LTO.
      -fno-tree-vectorize -fno-lto)
    set_target_properties(${target} PROPERTIES INTERPROCEDURAL_OPTIMIZATION OFF)
    target_link_libraries(${target} PRIVATE ${ARG_LINK})
    list(APPEND objects $<TARGET_OBJECTS:${target}>)
    list(APPEND definitions LANES_HAVE_KSET_${ISA})
  endforeach()
  set(LANES_KERNEL_OBJECTS "${objects}" PARENT_SCOPE)
  set(LANES_KERNEL_DEFINITIONS "${definitions}" PARENT_SCOPE)
endfunction()
