# Binned SAH BVH2, wide BVHs collapsed from it, and their statistics.
# Included from the top-level CMakeLists.txt.
add_library(lanes_bvh STATIC
  ${CMAKE_CURRENT_LIST_DIR}/bvh_build.c
  ${CMAKE_CURRENT_LIST_DIR}/bvh_wide.c
  ${CMAKE_CURRENT_LIST_DIR}/bvh_stats.c)
target_link_libraries(lanes_bvh PUBLIC lanes Threads::Threads m lanes_build_flags)

# Build times against Embree's on the same triangles.
find_package(embree 3 CONFIG QUIET)
if(embree_FOUND)
  add_executable(bench_bvh_build ${CMAKE_CURRENT_LIST_DIR}/../bench/bvh_build_bench.c)
  target_link_libraries(bench_bvh_build PRIVATE lanes_bvh embree)
else()
  message(STATUS "lanes: Embree 3 not found; bench_bvh_build is not built")
endif()
