# Fuzzing of every loader (label "fuzz"), and the replay of the committed
# corpus in every other build (label "scenes"). Included from
# tests/CMakeLists.txt.
#
#   CC=clang-14 CXX=clang++-14 cmake -S . -B out-fuzz -DLANES_FUZZ=ON
#   cmake --build out-fuzz -j2 --target lanes_fuzzers
#   ctest --test-dir out-fuzz -L fuzz -j2 --output-on-failure
#
# Each fuzz test runs one libFuzzer target for LANES_FUZZ_SECONDS on a copy
# of its seed corpus (tests/fuzz/corpus/<target>/) in the build directory,
# so the repo is never written and the copy keeps what earlier runs found.
# A crash, leak, UB report, contract violation, hang (-timeout) or
# oversized allocation (-malloc_limit_mb) fails the test; the input is
# saved under <build>/tests/fuzz/artifacts/<target>/ and replays with
#   out-fuzz/tests/fuzz/<target> <artifact>
# Inputs that once failed belong in the seed corpus: builds without
# LANES_FUZZ (gcc, LANES_SANITIZE) run each target's entry point once on
# every seed (fuzz_replay.<target>), so they stay fixed everywhere.
#
# The whole LANES_FUZZ build directory is instrumented (cmake/Sanitize.cmake):
# it is for fuzzing, not for the other tests.
option(LANES_FUZZ "Build the libFuzzer targets of tests/fuzz (clang only)" OFF)
set(LANES_FUZZ_SECONDS 60 CACHE STRING "How long each fuzz test runs (seconds)")
# A fixed seed makes a run repeatable: CI meets the same inputs each time,
# and a failure it reports can be reproduced. 0 lets libFuzzer pick one
# (longer local sessions explore more that way).
set(LANES_FUZZ_SEED 1 CACHE STRING "libFuzzer -seed of the fuzz tests (0: random)")

if(NOT TARGET lanes_scene)
  message(STATUS "lanes: no lanes_scene library; fuzz targets not added")
  return()
endif()

set(lanes_fuzz_dir ${CMAKE_CURRENT_LIST_DIR})
set(lanes_fuzz_targets
  fuzz_scene_file
  fuzz_mesh_obj
  fuzz_mesh_off
  fuzz_mesh_ply
  fuzz_mesh_ply_binary
  fuzz_mesh_stl
  fuzz_mesh_gltf
  fuzz_mesh_glb)

if(NOT LANES_FUZZ)
  foreach(t IN LISTS lanes_fuzz_targets)
    add_executable(replay_${t} ${lanes_fuzz_dir}/${t}.c ${lanes_fuzz_dir}/replay_main.c)
    target_link_libraries(replay_${t} PRIVATE lanes_scene)
    string(REGEX REPLACE "^fuzz_" "" short ${t})
    add_test(NAME fuzz_replay.${short} COMMAND replay_${t} ${lanes_fuzz_dir}/corpus/${t})
    set_tests_properties(fuzz_replay.${short} PROPERTIES LABELS scenes TIMEOUT 300)
  endforeach()
  return()
endif()

add_custom_target(lanes_fuzzers)
math(EXPR lanes_fuzz_timeout "${LANES_FUZZ_SECONDS} + 120")
foreach(t IN LISTS lanes_fuzz_targets)
  add_executable(${t} ${lanes_fuzz_dir}/${t}.c)
  target_link_libraries(${t} PRIVATE lanes_scene)
  target_link_options(${t} PRIVATE -fsanitize=fuzzer)
  set_target_properties(${t} PROPERTIES RUNTIME_OUTPUT_DIRECTORY
                        ${CMAKE_CURRENT_BINARY_DIR}/fuzz)
  add_dependencies(lanes_fuzzers ${t})

  set(dict "")
  if(EXISTS ${lanes_fuzz_dir}/${t}.dict)
    set(dict ${lanes_fuzz_dir}/${t}.dict)
  endif()
  string(REGEX REPLACE "^fuzz_" "" short ${t})
  add_test(NAME fuzz.${short}
    COMMAND ${CMAKE_COMMAND}
            -DFUZZER=$<TARGET_FILE:${t}>
            -DSEEDS=${lanes_fuzz_dir}/corpus/${t}
            -DCORPUS=${CMAKE_CURRENT_BINARY_DIR}/fuzz/corpus/${t}
            -DARTIFACTS=${CMAKE_CURRENT_BINARY_DIR}/fuzz/artifacts/${t}
            -DSECONDS=${LANES_FUZZ_SECONDS} -DSEED=${LANES_FUZZ_SEED}
            -DDICT=${dict}
            -P ${lanes_fuzz_dir}/run_fuzzer.cmake)
  set_tests_properties(fuzz.${short} PROPERTIES LABELS fuzz TIMEOUT ${lanes_fuzz_timeout})
endforeach()
