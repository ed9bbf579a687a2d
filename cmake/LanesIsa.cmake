# One source, many widths: the per-ISA kernel sources are compiled once per
# kernel set, each as its own OBJECT library with that set's flags and a
# LANES_KSET_<SET> definition (simd/simd.h turns it into the symbol suffix).
# Installed with the CMake package (find_package(lanes) includes it), so
# other projects build their own width-generic kernels the same way.
#
# Flags go on each target with target_compile_options: source-file
# properties are per directory and would leak one set's flags into all.

include(CheckCSourceCompiles)

# The sets come from their one list, simd/kernel_sets.h (installed as
# <lanes/simd/kernel_sets.h>; lanesConfig.cmake says where): LANES_ALL_ISAS
# (the names, in the enum's order) and per set LANES_ISA_<column>_<set> for
# the columns ID, LANES, FAMILY, EMULATED, RANK and AUTOMATIC.
if(NOT LANES_KERNEL_SETS_TABLE)
  set(LANES_KERNEL_SETS_TABLE ${CMAKE_CURRENT_LIST_DIR}/../simd/kernel_sets.h)
endif()
file(READ ${LANES_KERNEL_SETS_TABLE} lanes_set_table)
set(lanes_set_row_regex
    "\n *X\\(([A-Z0-9]+), *([a-z0-9]+), *([0-9]+), *([a-z0-9]+), *([01]), *([0-9]+), *([01]),")
string(REGEX MATCHALL "${lanes_set_row_regex}" lanes_set_rows "${lanes_set_table}")
set(LANES_ALL_ISAS "")
foreach(row IN LISTS lanes_set_rows)
  string(REGEX MATCH "${lanes_set_row_regex}" row "${row}")
  set(isa ${CMAKE_MATCH_2})
  list(APPEND LANES_ALL_ISAS ${isa})
  set(LANES_ISA_ID_${isa} ${CMAKE_MATCH_1})
  set(LANES_ISA_LANES_${isa} ${CMAKE_MATCH_3})
  set(LANES_ISA_FAMILY_${isa} ${CMAKE_MATCH_4})
  set(LANES_ISA_EMULATED_${isa} ${CMAKE_MATCH_5})
  set(LANES_ISA_RANK_${isa} ${CMAKE_MATCH_6})
  set(LANES_ISA_AUTOMATIC_${isa} ${CMAKE_MATCH_7})
endforeach()
if(NOT LANES_ALL_ISAS)
  message(FATAL_ERROR "no kernel sets found in ${LANES_KERNEL_SETS_TABLE}")
endif()

# What CMake adds per set: the compiler flags, the backend header
# simd/simd.h includes, the CPU features it needs as /proc/cpuinfo-like
# names (the tests' own statement, checked against the C table's: see
# tests/check_oracle.cmake), and below, a probe program.
set(LANES_ISA_FLAGS_scalar "")
set(LANES_ISA_HEADER_scalar vec1_scalar.h)
set(LANES_ISA_NEEDS_scalar sse2)

set(LANES_ISA_FLAGS_sse4 -msse4.1 -mpopcnt)
set(LANES_ISA_HEADER_sse4 vec4_sse4.h)
set(LANES_ISA_NEEDS_sse4 sse2 sse4.1 popcnt)

set(LANES_ISA_FLAGS_avx -mavx -mpopcnt)
set(LANES_ISA_HEADER_avx vec8_avx.h)
set(LANES_ISA_NEEDS_avx ${LANES_ISA_NEEDS_sse4} osxsave avx)

set(LANES_ISA_FLAGS_avx2 -mavx2 -mfma -mpopcnt)
set(LANES_ISA_HEADER_avx2 vec8_avx.h)
set(LANES_ISA_NEEDS_avx2 ${LANES_ISA_NEEDS_avx} avx2 fma)

set(LANES_ISA_FLAGS_avx512emu -mavx2 -mfma -mpopcnt)
set(LANES_ISA_HEADER_avx512emu vec16_avx512emu.h)
set(LANES_ISA_NEEDS_avx512emu ${LANES_ISA_NEEDS_avx2})

set(LANES_ISA_FLAGS_avx512 -mavx2 -mfma -mpopcnt -mavx512f -mavx512dq -mavx512bw -mavx512vl)
set(LANES_ISA_HEADER_avx512 vec16_avx512.h)
set(LANES_ISA_NEEDS_avx512 ${LANES_ISA_NEEDS_avx2} avx512f avx512dq avx512bw avx512vl)

# ymm registers only: the compiler may not widen anything to zmm, not even a
# struct copy (GCC needs -mmove-max/-mstore-max for those; clang follows
# the preferred width).
set(LANES_ISA_FLAGS_avx512vl8 ${LANES_ISA_FLAGS_avx512} -mprefer-vector-width=256)
if(CMAKE_C_COMPILER_ID STREQUAL "GNU" AND CMAKE_C_COMPILER_VERSION VERSION_GREATER_EQUAL 12)
  list(APPEND LANES_ISA_FLAGS_avx512vl8 -mmove-max=256 -mstore-max=256)
endif()
set(LANES_ISA_HEADER_avx512vl8 vec8_avx512vl.h)
set(LANES_ISA_NEEDS_avx512vl8 ${LANES_ISA_NEEDS_avx512})

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
set(LANES_ISA_PROBE_avx512vl8 "${LANES_ISA_PROBE_avx512}")

foreach(isa IN LISTS LANES_ALL_ISAS)
  if(NOT DEFINED LANES_ISA_FLAGS_${isa} OR NOT LANES_ISA_HEADER_${isa} OR NOT LANES_ISA_NEEDS_${isa}
     OR NOT LANES_ISA_PROBE_${isa})
    message(FATAL_ERROR "kernel set '${isa}' (simd/kernel_sets.h) needs LANES_ISA_FLAGS_${isa}, "
                        "_HEADER_, _NEEDS_ and _PROBE_${isa} in cmake/LanesIsa.cmake")
  endif()
endforeach()

# lanes_probe_isa(<set> <result-var>)
function(lanes_probe_isa isa out)
  set(CMAKE_REQUIRED_FLAGS "")
  string(REPLACE ";" " " flags "${LANES_ISA_FLAGS_${isa}}")
  set(CMAKE_REQUIRED_FLAGS "${flags}")
  set(CMAKE_REQUIRED_QUIET ON)
  check_c_source_compiles("${LANES_ISA_PROBE_${isa}}" LANES_PROBE_OK_${isa})
  set(${out} ${LANES_PROBE_OK_${isa}} PARENT_SCOPE)
endfunction()

# lanes_write_set_list(<file> <macro> <sets...>)
# Writes a header defining <macro>(X) as X(ID, name) for each set, so C code
# can generate its per-set tables (dispatch, test runners) from the sets a
# build actually compiled.
function(lanes_write_set_list file macro)
  set(rows "")
  foreach(isa IN LISTS ARGN)
    string(APPEND rows " X(${LANES_ISA_ID_${isa}}, ${isa})")
  endforeach()
  file(CONFIGURE OUTPUT ${file} CONTENT
       "/* Generated by CMake (lanes_write_set_list): the kernel sets built. */\n#define ${macro}(X)${rows}\n"
       @ONLY)
endfunction()

# lanes_add_kernel_sets(<target-prefix> SOURCES <files...> SETS <sets...>
#                       [LINK <targets...>])
# Creates <prefix>_<set> OBJECT libraries, one per set, each compiled with
# that set's flags, LANES_KSET_<ID> and -ffp-contract=off (FMA only where
# the code says vf_fmadd), and linked to LINK (default lanes::simd, the SIMD
# layer's headers). Writes <prefix>_sets.h into the current binary folder,
# defining <PREFIX>_SETS(X) as X(ID, name) per set (lanes_write_set_list).
# Sets in the caller's scope:
#   LANES_KERNEL_OBJECTS      their objects, to add to a library or program
#   LANES_KERNEL_DEFINITIONS  LANES_HAVE_KSET_<ID> for each set, for the
#                             baseline file that dispatches between them
#   LANES_KERNEL_SETS_HEADER  the path of <prefix>_sets.h
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
    set(ID ${LANES_ISA_ID_${isa}})
    set(target ${prefix}_${isa})
    add_library(${target} OBJECT ${ARG_SOURCES})
    # simd/simd.h derives the rest (suffix, name, enum value) from these.
    target_compile_definitions(${target} PRIVATE LANES_KSET_${ID} LANES_KSET_ID=${ID}
      LANES_KSET_TOKEN=${isa} LANES_KSET_LANES=${LANES_ISA_LANES_${isa}}
      "LANES_KSET_HEADER=\"${LANES_ISA_HEADER_${isa}}\"")
    target_compile_options(${target} PRIVATE ${LANES_ISA_FLAGS_${isa}} -ffp-contract=off
      # kernels run only what they say: no auto-vectoriser in the way of the
      # measured utilisation, and never into baseline code through LTO.
      -fno-tree-vectorize -fno-lto)
    set_target_properties(${target} PROPERTIES INTERPROCEDURAL_OPTIMIZATION OFF)
    target_link_libraries(${target} PRIVATE ${ARG_LINK})
    list(APPEND objects $<TARGET_OBJECTS:${target}>)
    list(APPEND definitions LANES_HAVE_KSET_${ID})
  endforeach()
  string(TOUPPER "${prefix}_SETS" macro)
  set(header ${CMAKE_CURRENT_BINARY_DIR}/${prefix}_sets.h)
  lanes_write_set_list(${header} ${macro} ${ARG_SETS})
  set(LANES_KERNEL_OBJECTS "${objects}" PARENT_SCOPE)
  set(LANES_KERNEL_DEFINITIONS "${definitions}" PARENT_SCOPE)
  set(LANES_KERNEL_SETS_HEADER "${header}" PARENT_SCOPE)
endfunction()
