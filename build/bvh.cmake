# Binned SAH BVH2, wide BVHs collapsed from it, and their statistics
# (bvh_build.c, bvh_wide.c, bvh_stats.c). Included from the top-level
# CMakeLists.txt.
# The builder is part of the library (the public API builds accels with
# it); lanes_bvh names it for the internal programs that use it directly.
add_library(lanes_bvh INTERFACE)
target_link_libraries(lanes_bvh INTERFACE lanes_internal)

# Build times against Embree's on the same triangles.
find_package(embree 3 CONFIG QUIET)
if(embree_FOUND)
  add_executable(bench_bvh_build ${CMAKE_CURRENT_LIST_DIR}/../bench/bvh_build_bench.c)
  target_link_libraries(bench_bvh_build PRIVATE lanes_bvh embree)
else()
  message(STATUS "lanes: Embree 3 not found; bench_bvh_build is not built")
endif()
