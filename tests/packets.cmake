# Packet traversal and the packet renderer against single-ray tracing.
add_executable(test_packets test_packets.c)
target_link_libraries(test_packets PRIVATE lanes_bvh lanes_internal)
add_test(NAME packets COMMAND test_packets)
set_tests_properties(packets PROPERTIES LABELS "packets" TIMEOUT 600)

add_executable(test_packet_render test_packet_render.c)
target_link_libraries(test_packet_render PRIVATE lanes_render)
add_test(NAME packet_render COMMAND test_packet_render)
set_tests_properties(packet_render PROPERTIES LABELS "packets" TIMEOUT 900)
if(TEST scenes.fetch_meshes)
  set_tests_properties(packet_render PROPERTIES FIXTURES_REQUIRED lanes_meshes
                       ENVIRONMENT "LANES_MESH_DIR=${LANES_MESH_DIR}")
endif()
