# Rendering at two kernel sets gives the same image (label "render"):
# scalar against the best set this CPU runs, PNGs compared with OpenImageIO.
# Included from tests/CMakeLists.txt.
add_executable(test_render_isa ${CMAKE_CURRENT_LIST_DIR}/test_render_isa.c)
target_link_libraries(test_render_isa PRIVATE lanes_render lanes_image)
set(lanes_render_dir ${CMAKE_CURRENT_BINARY_DIR}/render_isa)
file(MAKE_DIRECTORY ${lanes_render_dir})
add_test(NAME render.isa COMMAND test_render_isa ${lanes_render_dir})
# The scene plan and the accuracy modes in rendering (test_scene_plan.c).
add_executable(test_scene_plan ${CMAKE_CURRENT_LIST_DIR}/test_scene_plan.c)
target_link_libraries(test_scene_plan PRIVATE lanes_render)
add_test(NAME render.plan COMMAND test_scene_plan ${CMAKE_CURRENT_LIST_DIR}/data)
set_tests_properties(render.plan PROPERTIES LABELS render TIMEOUT 300)
# `lanes render --explain` says what the scene needs and where the mode
# came from; an unknown mode is a usage error (status 2).
add_test(NAME render.explain
  COMMAND lanes_cli render ${CMAKE_CURRENT_LIST_DIR}/data/scenes/ok/far_robust.json
          -o ${lanes_render_dir}/explain.png --size 32x32 --explain)
set_tests_properties(render.explain PROPERTIES LABELS render TIMEOUT 120
  PASS_REGULAR_EXPRESSION "shadow rays +on .*specular pass +off .*refraction +off .*accuracy +robust [(]from the scene file[)].*accuracy robust")
add_test(NAME render.bad_accuracy
  COMMAND bash -c "\"$0\" render -o \"$1\" --accuracy exact; test $? -eq 2"
          $<TARGET_FILE:lanes_cli> ${lanes_render_dir}/bad.png)
set_tests_properties(render.bad_accuracy PROPERTIES LABELS render TIMEOUT 60)
# The same scene at unit scale and scaled by 1e10 renders the same image
# (idiff, OpenImageIO's comparison): geometric normals and light areas are
# computed scale-safe (build/vec3.h, v3_unit_normal_area). Before, every
# surface of the 1e10 scene was black: normalizing a cross product squares
# the edges twice, and (1e10)^4 overflows a float.
find_program(LANES_IDIFF idiff REQUIRED)
add_test(NAME render.scale_1e10
  COMMAND bash -c "\"$0\" render \"$2/scale_1.json\" -o \"$3/scale_1.exr\" --size 64x64 &&
                   \"$0\" render \"$2/scale_1e10.json\" -o \"$3/scale_1e10.exr\" --size 64x64 &&
                   \"$1\" -fail 0.02 \"$3/scale_1.exr\" \"$3/scale_1e10.exr\""
          $<TARGET_FILE:lanes_cli> ${LANES_IDIFF} ${CMAKE_CURRENT_LIST_DIR}/data/scenes/ok ${lanes_render_dir})
set_tests_properties(render.scale_1e10 PROPERTIES LABELS render TIMEOUT 120)
set_tests_properties(render.isa PROPERTIES
  LABELS render TIMEOUT 600 SKIP_RETURN_CODE 77
  ENVIRONMENT_MODIFICATION "${LANES_TEST_ENV}")
# Robust mode on every set: its shadow rays leave the floor (y = 0) by one
# ulp, where the watertight t of the floor itself is +5.6e-9 against a true
# -3e-45; only the exact sign of t (trace/kernels/exact_sign.h) keeps the
# 8- and 16-wide sets, whose leaf boxes do not cull the floor, from
# shadowing it.
add_test(NAME render.isa.robust
  COMMAND test_render_isa ${lanes_render_dir} --size 64
          --scene ${CMAKE_CURRENT_LIST_DIR}/data/scenes/ok/scale_1.json --accuracy robust)
set_tests_properties(render.isa.robust PROPERTIES
  LABELS render TIMEOUT 600 SKIP_RETURN_CODE 77
  ENVIRONMENT_MODIFICATION "${LANES_TEST_ENV}")
# Every accuracy mode at scales 10^-17..10^17 and at growing distances from
# the origin: the unit-scale image, or a refusal naming the size limit
# (trace/scene_plan.h), with scalar and the best set (test_scale_sweep.c).
add_executable(test_scale_sweep ${CMAKE_CURRENT_LIST_DIR}/test_scale_sweep.c)
target_link_libraries(test_scale_sweep PRIVATE lanes_render lanes_image)
file(MAKE_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR}/scale_sweep)
add_test(NAME render.scale_sweep COMMAND test_scale_sweep ${CMAKE_CURRENT_BINARY_DIR}/scale_sweep)
set_tests_properties(render.scale_sweep PROPERTIES
  LABELS render TIMEOUT 600
  ENVIRONMENT_MODIFICATION "${LANES_TEST_ENV}")
# The stream renderer's material sort and shading utilisation.
add_executable(test_material_sort ${CMAKE_CURRENT_LIST_DIR}/test_material_sort.c)
target_link_libraries(test_material_sort PRIVATE lanes_render)
target_include_directories(test_material_sort PRIVATE ${CMAKE_CURRENT_LIST_DIR})
add_test(NAME render.material_sort COMMAND test_material_sort)
set_tests_properties(render.material_sort PROPERTIES LABELS render TIMEOUT 60)
# The path tracer against closed-form answers (test_paths.c).
add_executable(test_paths ${CMAKE_CURRENT_LIST_DIR}/test_paths.c)
target_link_libraries(test_paths PRIVATE lanes_render)
target_include_directories(test_paths PRIVATE ${CMAKE_CURRENT_LIST_DIR})
add_test(NAME render.paths COMMAND test_paths)
set_tests_properties(render.paths PROPERTIES LABELS render TIMEOUT 300)
# The generated materials of lanes paths --materials.
add_executable(test_material_assign ${CMAKE_CURRENT_LIST_DIR}/test_material_assign.c)
target_link_libraries(test_material_assign PRIVATE lanes_render)
target_include_directories(test_material_assign PRIVATE ${CMAKE_CURRENT_LIST_DIR})
add_test(NAME render.material_assign COMMAND test_material_assign)
set_tests_properties(render.material_assign PROPERTIES LABELS render TIMEOUT 60)
# The path tracer with many materials at every set: methods bit for bit,
# sets against scalar shading, packet utilisation by width.
add_executable(test_paths_sets ${CMAKE_CURRENT_LIST_DIR}/test_paths_sets.c)
target_link_libraries(test_paths_sets PRIVATE lanes_render)
target_include_directories(test_paths_sets PRIVATE ${CMAKE_CURRENT_LIST_DIR})
add_test(NAME render.paths_sets COMMAND test_paths_sets ${CMAKE_CURRENT_LIST_DIR}/data)
set_tests_properties(render.paths_sets PROPERTIES LABELS render TIMEOUT 300)
add_test(NAME render.paths_sets.sponza_bunny
         COMMAND test_paths_sets ${CMAKE_CURRENT_LIST_DIR}/data --builtin sponza-bunny)
set_tests_properties(render.paths_sets.sponza_bunny PROPERTIES
  LABELS render TIMEOUT 600 SKIP_RETURN_CODE 77 FIXTURES_REQUIRED lanes_meshes
  ENVIRONMENT "LANES_MESH_DIR=${LANES_MESH_DIR}")
