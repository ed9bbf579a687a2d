# Correctness tests of the kernels and of the SIMD layer (label "kernels").
# Included from tests/CMakeLists.txt.
#
#   ctest --test-dir out -L kernels -j2
#
# test_kernels: every kernel of every set this CPU runs against the
# double-precision references in reference.c, and the sets against each
# other. One ctest entry per family, so that ctest -j2 keeps both cores busy;
# each runs all sets in one process, because the cross-set comparisons need
# every set's results. `test_kernels --quick` (10^4 cases per kernel) is
# for emulators.
add_executable(test_kernels
  ${CMAKE_CURRENT_LIST_DIR}/test_kernels.c
  ${CMAKE_CURRENT_LIST_DIR}/test_kernels_box.c
  ${CMAKE_CURRENT_LIST_DIR}/test_kernels_tri.c
  ${CMAKE_CURRENT_LIST_DIR}/test_kernels_frustum.c
  ${CMAKE_CURRENT_LIST_DIR}/reference.c)
target_link_libraries(test_kernels PRIVATE lanes_internal)
target_include_directories(test_kernels PRIVATE ${CMAKE_CURRENT_LIST_DIR})

# The families are the rows of TK_FAMILIES in test_kernels_common.h.
file(READ ${CMAKE_CURRENT_LIST_DIR}/test_kernels_common.h lanes_tk_header)
string(REGEX MATCHALL "\n +X\\(([a-z_0-9]+)," lanes_tk_rows "${lanes_tk_header}")
set(lanes_kernel_families "")
foreach(row IN LISTS lanes_tk_rows)
  string(REGEX REPLACE "^\n +X\\(([a-z_0-9]+),$" "\\1" family "${row}")
  list(APPEND lanes_kernel_families ${family})
endforeach()
if(NOT lanes_kernel_families)
  message(FATAL_ERROR "no test families (TK_FAMILIES) in test_kernels_common.h")
endif()
set(lanes_kernel_tests "")
foreach(family IN LISTS lanes_kernel_families)
  add_test(NAME kernels.${family} COMMAND test_kernels --family ${family})
  list(APPEND lanes_kernel_tests kernels.${family})
endforeach()

# test_simd_ops: the SIMD layer, compiled once per kernel set exactly as the
# kernels are (same flags, same LANES_KSET_<SET> macro, same helper). The
# helper sets LANES_KERNEL_OBJECTS in this scope; the library's list must not
# be replaced by the tests' for whoever reads it after this file.
set(lanes_saved_kernel_objects "${LANES_KERNEL_OBJECTS}")
lanes_add_kernel_sets(test_simd_ops_set
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_simd_ops_set.c ${CMAKE_CURRENT_LIST_DIR}/test_simd_math_set.c
  SETS ${LANES_BUILT_ISAS}
  LINK lanes_build_flags)
set(lanes_simd_test_objects "${LANES_KERNEL_OBJECTS}")
set(LANES_KERNEL_OBJECTS "${lanes_saved_kernel_objects}")
foreach(isa IN LISTS LANES_BUILT_ISAS)
  target_include_directories(test_simd_ops_set_${isa} PRIVATE ${CMAKE_CURRENT_LIST_DIR})
endforeach()
add_executable(test_simd_ops ${CMAKE_CURRENT_LIST_DIR}/test_simd_ops.c ${lanes_simd_test_objects})
target_include_directories(test_simd_ops PRIVATE ${CMAKE_CURRENT_BINARY_DIR})
target_link_libraries(test_simd_ops PRIVATE lanes_internal)
target_include_directories(test_simd_ops PRIVATE ${CMAKE_CURRENT_LIST_DIR})
add_test(NAME kernels.simd_ops COMMAND test_simd_ops)
list(APPEND lanes_kernel_tests kernels.simd_ops)

# test_bsdf: the shaders' BSDFs (the bsdf kernels, trace/kernels/bsdf_core.h)
# at every set, against the double references of bsdf_reference.c: values,
# reciprocity, samples, albedo and chi-square.
add_executable(test_bsdf ${CMAKE_CURRENT_LIST_DIR}/test_bsdf.c ${CMAKE_CURRENT_LIST_DIR}/bsdf_reference.c)
target_include_directories(test_bsdf PRIVATE ${CMAKE_CURRENT_LIST_DIR})
target_link_libraries(test_bsdf PRIVATE lanes_internal)
add_test(NAME kernels.bsdf COMMAND test_bsdf)
list(APPEND lanes_kernel_tests kernels.bsdf)

# test_textures: the solid procedural textures (the texture_color and noise
# kernels, trace/kernels/texture_core.h) at every set, against the double
# reference of texture_reference.c.
add_executable(test_textures ${CMAKE_CURRENT_LIST_DIR}/test_textures.c ${CMAKE_CURRENT_LIST_DIR}/texture_reference.c)
target_include_directories(test_textures PRIVATE ${CMAKE_CURRENT_LIST_DIR})
target_link_libraries(test_textures PRIVATE lanes_internal)
add_test(NAME kernels.textures COMMAND test_textures)
list(APPEND lanes_kernel_tests kernels.textures)

# The exact sign of t that decides the watertight test's hits at t ~ 0
# (trace/kernels/exact_sign.h, plain C) against 128-bit integer arithmetic.
add_executable(test_exact_sign ${CMAKE_CURRENT_LIST_DIR}/test_exact_sign.c)
target_link_libraries(test_exact_sign PRIVATE lanes_internal)
add_test(NAME kernels.exact_sign COMMAND test_exact_sign)
list(APPEND lanes_kernel_tests kernels.exact_sign)

# The tests pick their sets themselves: the environment of whoever runs
# ctest must not narrow them.
set_tests_properties(${lanes_kernel_tests} PROPERTIES
  LABELS kernels TIMEOUT 600
  ENVIRONMENT_MODIFICATION "${LANES_TEST_ENV}")
