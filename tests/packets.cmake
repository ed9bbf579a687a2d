# Packet traversal and the packet renderer against single-ray tracing.
if(TARGET lanes_bvh)
  add_executable(test_packets test_packets.c)
  target_link_libraries(test_packets PRIVATE lanes_bvh lanes)
  add_test(NAME packets COMMAND test_packets)
  set_tests_properties(packets PROPERTIES LABELS "packets" TIMEOUT 600)
endif()
