# Rendering at two kernel sets gives the same image (label "render"):
# scalar against the best set this CPU runs, PNGs compared with OpenImageIO.
# Included from tests/CMakeLists.txt.
if(TARGET lanes_render AND TARGET lanes_image)
  add_executable(test_render_isa ${CMAKE_CURRENT_LIST_DIR}/test_render_isa.c)
  target_link_libraries(test_render_isa PRIVATE lanes_render lanes_image)
  set(lanes_render_dir ${CMAKE_CURRENT_BINARY_DIR}/render_isa)
  file(MAKE_DIRECTORY ${lanes_render_dir})
  add_test(NAME render.isa COMMAND test_render_isa ${lanes_render_dir})
  set_tests_properties(render.isa PROPERTIES
    LABELS render TIMEOUT 600 SKIP_RETURN_CODE 77
    ENVIRONMENT_MODIFICATION "LANES_ISA=unset:;LANES_MAX_ISA=unset:;LANES_DISABLE_CPU_FEATURES=unset:")
else()
  message(STATUS "lanes: no renderer or image library; render test not added")
endif()
