# Scene input: container, mesh import, scene files, built-in scenes and the
# malformed-input corpus (label "scenes"). Included from tests/CMakeLists.txt.
add_executable(test_scenes ${CMAKE_CURRENT_LIST_DIR}/test_scenes.c)
target_link_libraries(test_scenes PRIVATE lanes_scene)

set(lanes_scenes_scratch ${CMAKE_CURRENT_BINARY_DIR}/scenes_scratch)
file(MAKE_DIRECTORY ${lanes_scenes_scratch})
set(lanes_scenes_args ${CMAKE_CURRENT_LIST_DIR}/data ${lanes_scenes_scratch})

# Everything that needs no download.
add_test(NAME scenes COMMAND test_scenes ${lanes_scenes_args})

# The CGAL meshes: fetched first by a fixture (apt-get download of
# libcgal-demo, cached, checksummed; exit 77 = skipped when the archive is
# unreachable), then the scenes made from them. The test skips (77) when
# the meshes are still missing.
add_test(NAME scenes.fetch_meshes
         COMMAND ${PROJECT_SOURCE_DIR}/cmake/fetch_meshes.sh ${LANES_MESH_DIR})
set_tests_properties(scenes.fetch_meshes PROPERTIES
  FIXTURES_SETUP lanes_meshes SKIP_RETURN_CODE 77 TIMEOUT 600)
add_test(NAME scenes.meshes COMMAND test_scenes ${lanes_scenes_args} --meshes)
set_tests_properties(scenes.meshes PROPERTIES
  FIXTURES_REQUIRED lanes_meshes SKIP_RETURN_CODE 77 TIMEOUT 600)

# Both read the directory the fixture fills, whatever the caller's
# environment says.
set_tests_properties(scenes scenes.meshes PROPERTIES
  ENVIRONMENT "LANES_MESH_DIR=${LANES_MESH_DIR}")
set_tests_properties(scenes scenes.fetch_meshes scenes.meshes PROPERTIES LABELS "scenes")
