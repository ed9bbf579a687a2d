# `lanes compare` and the Embree adapter. Included from the top-level
# CMakeLists.txt (after lanes_render exists, before bench/), so paths are
# spelled from this file's directory.
#
#   lanes_embree_adapter  Embree scene, devices per ISA, ray layouts per API
#                         (also used by tests/test_traversal.c)
#   lanes_compare         the command (cmd_compare.c); the CLI links it and
#                         provides cli_common.c's helpers
find_package(embree 3 CONFIG QUIET)
if(NOT embree_FOUND)
  message(STATUS "lanes: Embree 3 not found; `lanes compare` and the Embree tests are not built")
elseif(NOT TARGET lanes_render)
  message(STATUS "lanes: no lanes_render target yet; `lanes compare` is not built")
else()
  add_library(lanes_embree_adapter STATIC ${CMAKE_CURRENT_LIST_DIR}/embree_adapter.c)
  target_link_libraries(lanes_embree_adapter PUBLIC embree lanes_render lanes_internal lanes_build_flags)

  add_library(lanes_compare STATIC ${CMAKE_CURRENT_LIST_DIR}/cmd_compare.c)
  target_link_libraries(lanes_compare PUBLIC lanes_embree_adapter lanes_render lanes_internal embree
                        Threads::Threads m lanes_build_flags)
endif()
