# Numerical extremes (label "kernels"): every kernel and traversal of every
# set this CPU runs, in every accuracy mode, against hand-derived
# expectations (signed zeros, denormals, 1e20 and 1e-20, NaN and Inf in
# rays, closed intervals, degenerate triangles, flat and empty boxes,
# inactive lanes). Included from tests/CMakeLists.txt.
#
#   ctest --test-dir out -R extremes --output-on-failure
add_executable(test_extremes ${CMAKE_CURRENT_LIST_DIR}/test_extremes.c)
target_link_libraries(test_extremes PRIVATE lanes_bvh lanes_scene lanes_internal)
add_test(NAME extremes COMMAND test_extremes)
# The test enumerates the sets itself: a LANES_* variable of whoever runs
# ctest must not narrow them.
set_tests_properties(extremes PROPERTIES
  LABELS kernels TIMEOUT 120
  ENVIRONMENT_MODIFICATION "${LANES_TEST_ENV}")

# The compiler must round floats where the source says so (see the test).
add_executable(test_float_narrowing ${CMAKE_CURRENT_LIST_DIR}/test_float_narrowing.c)
target_link_libraries(test_float_narrowing PRIVATE lanes_build_flags)
add_test(NAME float_narrowing COMMAND test_float_narrowing)
set_tests_properties(float_narrowing PROPERTIES LABELS kernels TIMEOUT 30)
