# BVH2 build, wide collapse and statistics. Included from tests/CMakeLists.txt.
add_executable(test_bvh ${CMAKE_CURRENT_LIST_DIR}/test_bvh.c)
target_link_libraries(test_bvh PRIVATE lanes_bvh)
target_compile_definitions(test_bvh PRIVATE
  LANES_DEFAULT_MESH_DIRS="${CMAKE_SOURCE_DIR}/out/meshes:${CMAKE_BINARY_DIR}/meshes")
add_test(NAME bvh COMMAND test_bvh)
# Real meshes ($LANES_MESH_DIR, or out/meshes): skipped when there are none.
add_test(NAME bvh_meshes COMMAND test_bvh --meshes)
set_tests_properties(bvh bvh_meshes PROPERTIES LABELS "bvh")
set_tests_properties(bvh_meshes PROPERTIES SKIP_RETURN_CODE 77)
