# System tests: the CLI's choice of kernel set (label "dispatch"), the
# separation of the sets in the object files (label "hygiene"), the choice on
# emulated CPUs (label "qemu"), and a smoke run of the main job's benchmark
# (label "cli"). Included by tests/CMakeLists.txt.
#
#   ctest --test-dir out -L dispatch     (or -L hygiene, -L qemu, -L cli)
#
# Expectations are computed by tests/check_oracle.cmake from an independent
# statement of what each set needs and what the CPU offers (/proc/cpuinfo, or
# the emulated model's feature list below), never from the detector under
# test.

set(LANES_CHECK_CLI ${CMAKE_CURRENT_SOURCE_DIR}/check_cli.cmake)
set(LANES_CHECK_HYGIENE ${CMAKE_CURRENT_SOURCE_DIR}/check_hygiene.sh)
string(REPLACE ";" "," lanes_compiled_csv "${LANES_BUILT_ISAS}")
# Tests must not see a LANES_* variable of whoever runs ctest.
set(lanes_clean_env
    "${LANES_TEST_ENV}")

# The CLI executable (OUTPUT_NAME lanes); the library already owns the
# target name "lanes".
set(lanes_cli_target "")
foreach(candidate IN ITEMS lanes_cli lanes-cli lanes_exe)
  if(TARGET ${candidate})
    set(lanes_cli_target ${candidate})
    break()
  endif()
endforeach()

# ---------------------------------------------------------------------------
# dispatch: `lanes info --json` under every way of choosing a set
# ---------------------------------------------------------------------------
# lanes_cli_test(<name> <label> [VAR=value...]): the values become -D options
# of check_cli.cmake.
function(lanes_cli_test name label)
  set(defs "")
  foreach(kv IN LISTS ARGN)
    list(APPEND defs "-D${kv}")
  endforeach()
  add_test(NAME ${name}
    COMMAND ${CMAKE_COMMAND} -DCLI=$<TARGET_FILE:${lanes_cli_target}>
            -DCOMPILED=${lanes_compiled_csv} ${defs} -P ${LANES_CHECK_CLI})
  set_tests_properties(${name} PROPERTIES
    LABELS ${label} SKIP_REGULAR_EXPRESSION "SKIP:" TIMEOUT 120
    ENVIRONMENT_MODIFICATION "${LANES_TEST_ENV}")
endfunction()

if(lanes_cli_target)
  lanes_cli_test(dispatch.auto dispatch)
  # A forced set this CPU cannot run (avx512 on a Zen 3) must be refused,
  # naming the real cause: check_cli.cmake expects that then.
  foreach(isa IN LISTS LANES_BUILT_ISAS)
    lanes_cli_test(dispatch.env.${isa} dispatch ENV_ISA=${isa})
    lanes_cli_test(dispatch.flag.${isa} dispatch FLAG_ISA=${isa})
    lanes_cli_test(dispatch.max.${isa} dispatch ENV_MAX=${isa})
  endforeach()
  foreach(isa IN LISTS LANES_ALL_ISAS)
    if(NOT isa IN_LIST LANES_BUILT_ISAS)
      lanes_cli_test(dispatch.not_compiled.${isa} dispatch ENV_ISA=${isa} EXPECT=reject
                     "EXPECT_MESSAGE=not compiled")
    endif()
  endforeach()

  # Names that are no set: exit 2, and the message lists the real ones.
  lanes_cli_test(dispatch.bogus.env dispatch ENV_ISA=bogus EXPECT=reject)
  lanes_cli_test(dispatch.bogus.flag dispatch FLAG_ISA=bogus EXPECT=reject)
  lanes_cli_test(dispatch.bogus.max dispatch ENV_MAX=bogus EXPECT=reject
                 "EXPECT_MESSAGE=LANES_MAX_ISA")

  # Precedence: the flag (an API call) beats LANES_ISA, which beats the cap.
  list(LENGTH LANES_BUILT_ISAS lanes_built_count)
  if(lanes_built_count GREATER 1)
    list(GET LANES_BUILT_ISAS 1 lanes_second)
    lanes_cli_test(dispatch.precedence.flag_over_env dispatch ENV_ISA=scalar
                   FLAG_ISA=${lanes_second})
    lanes_cli_test(dispatch.precedence.force_over_cap dispatch ENV_MAX=scalar
                   ENV_ISA=${lanes_second})
  endif()

  # The test-only switch walks the automatic choice down every step.
  lanes_cli_test(dispatch.disable.1_avx512f dispatch ENV_DISABLE=avx512f)
  lanes_cli_test(dispatch.disable.2_avx2 dispatch ENV_DISABLE=avx512f,avx2)
  lanes_cli_test(dispatch.disable.3_avx dispatch ENV_DISABLE=avx512f,avx2,avx)
  lanes_cli_test(dispatch.disable.4_sse4.1 dispatch ENV_DISABLE=avx512f,avx2,avx,sse4.1)
  # Any one missing feature of a set's chain is enough to drop it.
  lanes_cli_test(dispatch.disable.fma dispatch ENV_DISABLE=fma)
  lanes_cli_test(dispatch.disable.osxsave dispatch ENV_DISABLE=osxsave)
  lanes_cli_test(dispatch.disable.popcnt dispatch ENV_DISABLE=popcnt)
  lanes_cli_test(dispatch.disable.avx512vl dispatch ENV_DISABLE=avx512vl)

  # Forcing a set whose feature is switched off: exit 2 naming the cause,
  # never a silent fallback. The oracle works out which cause the message
  # must give on this CPU (on one without AVX-512 the CPU, not the switch,
  # is why avx512 cannot run).
  set(lanes_refusals
      "avx512|avx512f|ENV" "avx512|avx512bw|FLAG" "avx512emu|avx2|ENV" "avx2|avx2|ENV"
      "avx2|fma|FLAG" "avx|avx|ENV" "avx|osxsave|ENV" "sse4|sse4.1|ENV" "sse4|popcnt|FLAG"
      "avx512vl8|avx512vl|FLAG")
  foreach(r IN LISTS lanes_refusals)
    string(REPLACE "|" ";" r "${r}")
    list(GET r 0 isa)
    list(GET r 1 feature)
    list(GET r 2 how)
    if(isa IN_LIST LANES_BUILT_ISAS)
      lanes_cli_test(dispatch.refuse.${isa}_without_${feature} dispatch
                     ${how}_ISA=${isa} ENV_DISABLE=${feature} EXPECT=reject)
    endif()
  endforeach()

  # A name in the switch that is no feature is an error, as in LANES_ISA;
  # --isa does not excuse it.
  lanes_cli_test(dispatch.disable.unknown dispatch ENV_DISABLE=avx2,avx513)
  lanes_cli_test(dispatch.disable.unknown_with_flag dispatch ENV_DISABLE=sse5 FLAG_ISA=scalar)

  # The emulated 16 lanes need AVX2, not AVX-512.
  if(avx512emu IN_LIST LANES_BUILT_ISAS)
    lanes_cli_test(dispatch.avx512emu_without_avx512 dispatch ENV_ISA=avx512emu
                   ENV_DISABLE=avx512f,avx512cd,avx512dq,avx512bw,avx512vl)
  endif()

  # The reason for a refusal on CPU states this machine is not (Zen 3, an
  # OS without ZMM state, noxsave).
  add_executable(test_cpu_explain ${CMAKE_CURRENT_SOURCE_DIR}/test_cpu_explain.c)
  target_link_libraries(test_cpu_explain PRIVATE lanes_internal)
  add_test(NAME dispatch.explain_missing COMMAND test_cpu_explain)
  set_tests_properties(dispatch.explain_missing PROPERTIES LABELS dispatch TIMEOUT 60)

  # The kernel tests test exactly the sets this CPU runs, as the oracle sees
  # it, and skip the others: a detector that wrongly said "no" would
  # otherwise leave them green while testing nothing.
  foreach(binary IN ITEMS test_kernels test_simd_ops)
    if(TARGET ${binary})
      set(args "")
      if(binary STREQUAL "test_kernels")
        set(args "--quick,--family,meta")
      endif()
      add_test(NAME dispatch.sets_tested.${binary}
        COMMAND ${CMAKE_COMMAND} -DCOMPILED=${lanes_compiled_csv} -DBINARY=$<TARGET_FILE:${binary}>
                -DARGS=${args} -DCHECK_SETS=ON -P ${CMAKE_CURRENT_SOURCE_DIR}/check_run_sets.cmake)
      set_tests_properties(dispatch.sets_tested.${binary} PROPERTIES LABELS dispatch TIMEOUT 300
        ENVIRONMENT_MODIFICATION "${LANES_TEST_ENV}")
    endif()
  endforeach()

  # The CLI's benchmarks name the compiler that built them. The expected name is
  # CMake's reading of the compiler (its id and version); both come from the
  # compiler's own version macros, so this catches a wrong branch, a
  # fallback or a format slip in cli_compiler(), not a lying compiler.
  if(CMAKE_C_COMPILER_ID STREQUAL "Clang")
    set(lanes_expected_compiler "clang ${CMAKE_C_COMPILER_VERSION}")
  elseif(CMAKE_C_COMPILER_ID STREQUAL "GNU")
    set(lanes_expected_compiler "gcc ${CMAKE_C_COMPILER_VERSION}")
  endif()
  if(lanes_expected_compiler)
    add_test(NAME cli.compiler
      COMMAND bash -c "json=$(\"$0\" info --json) && text=$(\"$0\" info) && grep -F \"\\\"compiler\\\": \\\"$1\\\"\" <<< \"$json\" && grep -Fx \"compiler:     $1\" <<< \"$text\""
              $<TARGET_FILE:${lanes_cli_target}> "${lanes_expected_compiler}")
    set_tests_properties(cli.compiler PROPERTIES LABELS cli TIMEOUT 60)
  endif()

  # Output paths: missing folders are made; a path that cannot be written
  # is refused with the path and the OS's reason, status 2.
  set(lanes_out_test ${CMAKE_CURRENT_BINARY_DIR}/cli_outputs)
  add_test(NAME cli.output_folders
    COMMAND bash -c "rm -rf \"$1\" && \"$0\" render -o \"$1/new/deeper/x.png\" --size 8x8 && test -s \"$1/new/deeper/x.png\""
            $<TARGET_FILE:${lanes_cli_target}> ${lanes_out_test})
  # (The message is checked in the script: a PASS_REGULAR_EXPRESSION would
  # make ctest ignore the exit status.)
  add_test(NAME cli.output_unwritable
    COMMAND bash -c "out=$(\"$0\" render -o /proc/lanes-no-such-folder/x.png --size 8x8 2>&1); s=$?; echo \"$out\"; test $s -eq 2 && grep -q 'cannot create /proc/lanes-no-such-folder: No such file or directory' <<< \"$out\""
            $<TARGET_FILE:${lanes_cli_target}>)
  # A folder that exists but a file that cannot be made there: the OS's
  # reason, not only the image library's.
  add_test(NAME cli.image_unwritable
    COMMAND bash -c "out=$(\"$0\" render -o /proc/lanes-no-such-file.png --size 8x8 2>&1); s=$?; echo \"$out\"; test $s -eq 2 && grep -q '/proc/lanes-no-such-file.png: cannot write: No such file or directory' <<< \"$out\""
            $<TARGET_FILE:${lanes_cli_target}>)
  # lanes compare opens its --csv file first: a bad path fails at once,
  # before any measuring (no table printed).
  add_test(NAME cli.compare_csv_unwritable
    COMMAND bash -c "out=$(\"$0\" compare --quick --csv /proc/lanes-no-such-folder/x.csv 2>&1); s=$?; echo \"$out\"; test $s -eq 2 && grep -q 'compare: --csv: cannot create /proc/lanes-no-such-folder' <<< \"$out\" && ! grep -q Mrays <<< \"$out\""
            $<TARGET_FILE:${lanes_cli_target}>)
  set_tests_properties(cli.compare_csv_unwritable PROPERTIES TIMEOUT 60)
  # --packet: the range in the message is the rule that is applied.
  foreach(pair IN ITEMS "sse4|2|4" "avx2|8|16")
    string(REPLACE "|" ";" pair "${pair}")
    list(GET pair 0 isa)
    list(GET pair 1 packet)
    list(GET pair 2 smallest)
    if(isa IN_LIST LANES_BUILT_ISAS)
      add_test(NAME cli.packet_range.${isa}
        COMMAND bash -c "\"$0\" --isa ${isa} render -o \"$1/p.png\" --scheme packet --packet ${packet} --size 8x8; \
                         test $? -eq 2 && \"$0\" --isa ${isa} render -o \"$1/p.png\" --scheme packet --packet ${smallest} --size 8x8"
                $<TARGET_FILE:${lanes_cli_target}> ${lanes_out_test})
      set_tests_properties(cli.packet_range.${isa} PROPERTIES
        PASS_REGULAR_EXPRESSION "--packet ${packet} out of range [(]${smallest}[.][.]1024 at ${isa}.*wrote")
      list(APPEND lanes_output_tests cli.packet_range.${isa})
      break()
    endif()
  endforeach()
  # lanes paths: an image and its measurements as JSON; bad options exit 2
  # naming the option and its range.
  add_test(NAME cli.paths
    COMMAND bash -c "set -e; out=$(\"$0\" paths --size 16x16 --spp 2 --json -o \"$1/paths.exr\"); echo \"$out\"; \
                     grep -q '\"shading_utilization\": 1' <<< \"$out\"; test -s \"$1/paths.exr\"; \
                     out=$(\"$0\" paths --size 16x16 --spp 2 --json --method stream --stream 256); echo \"$out\"; \
                     grep -q '\"stage_seconds\": {\"generate\"' <<< \"$out\"; \
                     \"$0\" paths --size 16x16 --spp 1 --method packet --csv \"$1/paths.csv\" > /dev/null; grep -q ',default,packet,lanes,' \"$1/paths.csv\"; grep -q '^cpu,scene,method' \"$1/paths.csv\"; \
                     for bad in '--spp 0' '--depth 33' '--method bogus' '--background -1' '--stream 100' '--stream 1000' '--materials 0' '--assign everywhere'; do \
                       set +e; msg=$(\"$0\" paths --size 8x8 $bad 2>&1); s=$?; set -e; echo \"$bad: $s: $msg\" | head -2; \
                       test $s -eq 2; grep -q -- \"$\{bad%% *\}\" <<< \"$msg\"; done"
            $<TARGET_FILE:${lanes_cli_target}> ${lanes_out_test})
  list(APPEND lanes_output_tests cli.paths)
  # lanes paths --intersector embree: Embree's rtcIntersect1M traces the
  # stream's rays and the image is lanes' own but for the paths that float
  # rounding sends elsewhere (at most 2% of pixels off by over 0.05).
  if(TARGET lanes_compare)
    find_program(LANES_IDIFF idiff REQUIRED)
    add_test(NAME cli.paths_embree
      COMMAND bash -c "set -e; for x in lanes embree; do out=$(\"$0\" paths --size 64x64 --spp 4 --method stream --stream 256 --materials 36 --intersector $x --json -o \"$1/paths_$x.exr\"); echo \"$out\"; \
                       grep -q \"\\\"intersector\\\": \\\"$x\\\"\" <<< \"$out\"; done; \
                       set +e; \"$2\" -fail 0.05 -failpercent 2 \"$1/paths_lanes.exr\" \"$1/paths_embree.exr\"; s=$?; set -e; test $s -le 1; \
                       set +e; msg=$(\"$0\" paths --size 8x8 --intersector optix 2>&1); s=$?; set -e; echo \"$msg\"; test $s -eq 2; grep -q optix <<< \"$msg\""
              $<TARGET_FILE:${lanes_cli_target}> ${lanes_out_test} ${LANES_IDIFF})
    list(APPEND lanes_output_tests cli.paths_embree)
  endif()
  # lanes study: the Node width table and its single-ray rows' utilisation
  # (columns 20, 21), a fraction in (0, 1]; the scalar set tests only real
  # triangles, so its leaf utilisation is exactly 1.
  add_test(NAME cli.study
    COMMAND bash -c "set -e; rm -rf \"$1/study\"; \"$0\" study --reps 1 --size 32x32 --out \"$1/study\" > /dev/null 2>&1; \
                     grep -q '^## Node width' \"$1/study/tables.md\"; grep -q '% / [0-9]*%) |' \"$1/study/tables.md\"; \
                     awk -F, 'NR == 1 && ($20 != \"util_node\" || $21 != \"util_leaf\") { bad = 1 } \
                              NR > 1 && ($3 == \"wide\" || $3 == \"wide-nodes\") { n++; \
                                if (!($20 > 0 && $20 <= 1 && $21 > 0 && $21 <= 1)) bad = 1; if ($4 == \"scalar\" && $21 != 1) bad = 1 } \
                              END { exit bad || n < 3 }' \"$1/study/measurements.csv\""
            $<TARGET_FILE:${lanes_cli_target}> ${lanes_out_test})
  list(APPEND lanes_output_tests cli.study)
  # lanes study --paths: its four experiments in the CSV, the tables.
  add_test(NAME cli.study_paths
    COMMAND bash -c "set -e; rm -rf \"$1/study_paths\"; \"$0\" study --paths --reps 1 --size 32x32 --out \"$1/study_paths\" > /dev/null; \
                     for e in methods stream materials clustered; do grep -q \",$e,\" \"$1/study_paths/paths.csv\"; done; \
                     grep -q 'stream size' \"$1/study_paths/tables.md\"; grep -q 'packet.s shading s / this' \"$1/study_paths/tables.md\"; grep -q ',engine,stream,embree,' \"$1/study_paths/paths.csv\"; \
                     f=\"$1/study_paths/stream_intersect.csv\"; grep -q ',trace_wide (AoS),lanes,' \"$f\"; \
                     grep -q ',lanes_intersect_stream (SoA),lanes,' \"$f\"; grep -q ',rtcIntersectNp,embree,' \"$f\"; \
                     awk -F, 'NR > 1 && ($5 == 0 || ($4 == \"lanes\" && $8 != 0) || $8 * 100 > $5) { bad = 1 } END { exit bad }' \"$f\"; \
                     grep -q 'SoA call / AoS trace_wide' \"$1/study_paths/tables.md\""
            $<TARGET_FILE:${lanes_cli_target}> ${lanes_out_test})
  list(APPEND lanes_output_tests cli.study_paths)
  set_tests_properties(cli.output_folders cli.output_unwritable cli.image_unwritable ${lanes_output_tests} PROPERTIES
    LABELS cli TIMEOUT 120 ENVIRONMENT_MODIFICATION "${LANES_TEST_ENV}")

  # The main job's benchmark runs and reports every set this CPU runs.
  add_test(NAME cli.bench_kernels_quick
    COMMAND ${CMAKE_COMMAND} -DCLI=$<TARGET_FILE:${lanes_cli_target}>
            -DCSV=${CMAKE_CURRENT_BINARY_DIR}/bench_kernels_quick.csv
            -P ${CMAKE_CURRENT_SOURCE_DIR}/check_bench.cmake)
  # RUN_SERIAL: timing loops pinned to one core; not alongside other tests.
  set_tests_properties(cli.bench_kernels_quick PROPERTIES
    LABELS cli TIMEOUT 300 RUN_SERIAL TRUE ENVIRONMENT_MODIFICATION "${LANES_TEST_ENV}")

  # The instruction classes its resource bound charges.
  add_executable(test_kernel_model ${CMAKE_CURRENT_SOURCE_DIR}/test_kernel_model.c
                 ${PROJECT_SOURCE_DIR}/bench/kernel_model.c ${PROJECT_SOURCE_DIR}/bench/cli_common.c)
  target_link_libraries(test_kernel_model PRIVATE lanes_internal ${CMAKE_DL_LIBS})
  add_test(NAME cli.kernel_model_classes COMMAND test_kernel_model)
  set_tests_properties(cli.kernel_model_classes PROPERTIES LABELS cli TIMEOUT 60)
else()
  message(STATUS "lanes: no CLI target yet; dispatch and qemu tests of `lanes info` not added")
endif()

# ---------------------------------------------------------------------------
# hygiene: symbols, sections and instructions of the object files
# ---------------------------------------------------------------------------
function(lanes_hygiene_test name)
  add_test(NAME ${name} COMMAND bash ${LANES_CHECK_HYGIENE} ${ARGN})
  set_tests_properties(${name} PROPERTIES LABELS hygiene TIMEOUT 120)
endfunction()

set(lanes_all_kernel_objects "")
foreach(isa IN LISTS LANES_BUILT_ISAS)
  lanes_hygiene_test(hygiene.symbols.${isa} symbols ${isa} $<TARGET_OBJECTS:lanes_kernels_${isa}>)
  list(APPEND lanes_all_kernel_objects $<TARGET_OBJECTS:lanes_kernels_${isa}>)
endforeach()
lanes_hygiene_test(hygiene.no_constructors sections - ${lanes_all_kernel_objects})

# Baseline code runs before dispatch: SSE2 at most. Scalar kernels too.
set(lanes_baseline_objects $<TARGET_OBJECTS:lanes_simd_objects> $<TARGET_OBJECTS:lanes_trace_objects>)
if(scalar IN_LIST LANES_BUILT_ISAS)
  list(APPEND lanes_baseline_objects $<TARGET_OBJECTS:lanes_kernels_scalar>)
endif()
lanes_hygiene_test(hygiene.isa.baseline isa baseline ${lanes_baseline_objects})
# The same for the rest of the project's own code (the CLI, the builders,
# ...): every target outside tests/ that is not a kernel set and carries no
# -m flag of its own. Test programs may build per-set code on purpose.
function(lanes_collect_targets dir out)
  get_property(targets DIRECTORY ${dir} PROPERTY BUILDSYSTEM_TARGETS)
  get_property(subdirs DIRECTORY ${dir} PROPERTY SUBDIRECTORIES)
  foreach(sub IN LISTS subdirs)
    lanes_collect_targets(${sub} more)
    list(APPEND targets ${more})
  endforeach()
  set(${out} "${targets}" PARENT_SCOPE)
endfunction()
lanes_collect_targets(${CMAKE_SOURCE_DIR} lanes_targets)
set(lanes_program_targets "")
set(lanes_program_objects "")
foreach(t IN LISTS lanes_targets)
  get_target_property(type ${t} TYPE)
  get_target_property(dir ${t} SOURCE_DIR)
  get_target_property(options ${t} COMPILE_OPTIONS)
  if(NOT type MATCHES "^(EXECUTABLE|STATIC_LIBRARY|SHARED_LIBRARY|OBJECT_LIBRARY|MODULE_LIBRARY)$"
     OR t MATCHES "^lanes_kernels_" OR t MATCHES "^lanes_(simd|trace)_objects$"
     # the libraries are made of the objects checked here and the kernels
     OR t STREQUAL "lanes" OR t STREQUAL "lanes_shared"
     OR dir STREQUAL CMAKE_CURRENT_SOURCE_DIR OR "${options}" MATCHES "(^|;)-m")
    continue()
  endif()
  list(APPEND lanes_program_targets ${t})
  list(APPEND lanes_program_objects $<TARGET_OBJECTS:${t}>)
endforeach()
if(lanes_program_objects)
  string(REPLACE ";" ", " shown "${lanes_program_targets}")
  message(STATUS "lanes: hygiene.isa.program checks the objects of: ${shown}")
  lanes_hygiene_test(hygiene.isa.program isa baseline ${lanes_program_objects})
endif()
# Every set the script has a level for (its --levels) is checked at it.
execute_process(COMMAND bash ${LANES_CHECK_HYGIENE} --levels OUTPUT_VARIABLE lanes_hygiene_levels
                COMMAND_ERROR_IS_FATAL ANY)
string(REPLACE "\n" ";" lanes_hygiene_levels "${lanes_hygiene_levels}")
foreach(isa IN LISTS LANES_BUILT_ISAS)
  if(isa IN_LIST lanes_hygiene_levels)
    lanes_hygiene_test(hygiene.isa.${isa} isa ${isa} $<TARGET_OBJECTS:lanes_kernels_${isa}>)
  endif()
endforeach()

# The pipe-rate probes of `lanes bench kernels` (bench/pipe_probes_*.c)
lanes_hygiene_test(hygiene.isa.pipe_probes_avx isa avx $<TARGET_OBJECTS:lanes_pipe_probes_avx>)
lanes_hygiene_test(hygiene.isa.pipe_probes_fma isa avx2 $<TARGET_OBJECTS:lanes_pipe_probes_fma>)

# The checks must be able to fail: each one is also run where it has to find
# something (a wider set's objects, another set's suffix, a constructor).
set(lanes_hygiene_catches
    "sse4|baseline" "avx|sse4" "avx2|sse4" "avx2|avx" "avx512|avx2" "avx512vl8|avx2"
    "avx512|avx512vl8")
foreach(pair IN LISTS lanes_hygiene_catches)
  string(REPLACE "|" ";" pair "${pair}")
  list(GET pair 0 wider)
  list(GET pair 1 level)
  if(wider IN_LIST LANES_BUILT_ISAS)
    lanes_hygiene_test(hygiene.catches.${wider}_above_${level} --expect-violation isa ${level}
                       $<TARGET_OBJECTS:lanes_kernels_${wider}>)
  endif()
endforeach()
list(GET LANES_BUILT_ISAS -1 lanes_widest)
lanes_hygiene_test(hygiene.catches.foreign_suffix --expect-violation symbols foreign
                   $<TARGET_OBJECTS:lanes_kernels_${lanes_widest}>)
# A generated object with a load-time constructor, built only for this test.
# The constructor calls an external function: clang evaluates a constructor
# that only stores a constant at compile time and drops it. The object is
# never linked.
file(WRITE ${CMAKE_CURRENT_BINARY_DIR}/hygiene_constructor.c
     "/* Generated by tests/system.cmake: must be caught by the constructor check. */\n"
     "int lanes_hygiene_probe_value;\n"
     "int lanes_hygiene_probe_external(void);\n"
     "__attribute__((constructor)) static void lanes_hygiene_probe_init(void)\n"
     "{ lanes_hygiene_probe_value = lanes_hygiene_probe_external(); }\n")
add_library(lanes_hygiene_probe OBJECT ${CMAKE_CURRENT_BINARY_DIR}/hygiene_constructor.c)
lanes_hygiene_test(hygiene.catches.constructor --expect-violation sections -
                   $<TARGET_OBJECTS:lanes_hygiene_probe>)

# ---------------------------------------------------------------------------
# qemu: the choice on CPUs this machine is not
# ---------------------------------------------------------------------------
# qemu's TCG checks features per instruction and not for all of them (it runs
# SSE4.1 on core2duo), and it runs no AVX-512 at all; so these tests check the
# *decision* on each model, while the hygiene tests guard the instructions.
find_program(LANES_QEMU_X86_64 qemu-x86_64)

# The features each model offers, in simd/cpu.c's names, as qemu 7.2 defines
# the models (checked with a cpuid probe). "Haswell,-xsave" has AVX2 in
# cpuid but no XSAVE, so no OS can enable YMM state: nothing AVX is usable.
set(lanes_qemu_models core2duo Nehalem SandyBridge Haswell Haswell-noxsave)
set(lanes_qemu_cpu_core2duo core2duo)
set(lanes_qemu_cpu_Nehalem Nehalem)
set(lanes_qemu_cpu_SandyBridge SandyBridge)
set(lanes_qemu_cpu_Haswell Haswell)
set(lanes_qemu_cpu_Haswell-noxsave "Haswell,-xsave")
set(lanes_qemu_features_core2duo sse2,sse3,ssse3)
set(lanes_qemu_features_Nehalem ${lanes_qemu_features_core2duo},sse4.1,sse4.2,popcnt)
set(lanes_qemu_features_SandyBridge ${lanes_qemu_features_Nehalem},osxsave,avx)
set(lanes_qemu_features_Haswell
    ${lanes_qemu_features_SandyBridge},f16c,fma,avx2,bmi1,bmi2,lzcnt)
set(lanes_qemu_features_Haswell-noxsave ${lanes_qemu_features_Nehalem},bmi1,bmi2,lzcnt)

# Without qemu every qemu test is still listed, and reports itself skipped.
function(lanes_qemu_skip name)
  add_test(NAME ${name} COMMAND bash -c
    "echo 'SKIP: qemu-x86_64 not found (Debian package qemu-user; cmake/setup.sh installs it)'; exit 77")
  set_tests_properties(${name} PROPERTIES LABELS qemu SKIP_RETURN_CODE 77)
endfunction()

function(lanes_qemu_cli_test name model)
  if(LANES_QEMU_X86_64)
    lanes_cli_test(${name} qemu QEMU=${LANES_QEMU_X86_64} "QEMU_CPU=${lanes_qemu_cpu_${model}}"
                   FEATURES=${lanes_qemu_features_${model}} ${ARGN})
  else()
    lanes_qemu_skip(${name})
  endif()
endfunction()

if(lanes_cli_target)
  foreach(model IN LISTS lanes_qemu_models)
    lanes_qemu_cli_test(qemu.${model}.info ${model})
  endforeach()
  # Refusals on a CPU that really lacks the set: exit 2 and a message, not
  # SIGILL (qemu would die of it: it cannot execute AVX-512 at all).
  if(avx512 IN_LIST LANES_BUILT_ISAS)
    lanes_qemu_cli_test(qemu.Haswell.refuse_avx512 Haswell ENV_ISA=avx512 EXPECT=reject
                        EXPECT_MESSAGE=avx512f)
  endif()
  if(avx2 IN_LIST LANES_BUILT_ISAS)
    lanes_qemu_cli_test(qemu.Nehalem.refuse_avx2 Nehalem ENV_ISA=avx2 EXPECT=reject)
    lanes_qemu_cli_test(qemu.SandyBridge.refuse_avx2 SandyBridge FLAG_ISA=avx2 EXPECT=reject)
  endif()
  if(avx IN_LIST LANES_BUILT_ISAS)
    lanes_qemu_cli_test(qemu.Haswell-noxsave.refuse_avx Haswell-noxsave ENV_ISA=avx EXPECT=reject)
  endif()
  if(sse4 IN_LIST LANES_BUILT_ISAS)
    lanes_qemu_cli_test(qemu.core2duo.refuse_sse4 core2duo ENV_ISA=sse4 EXPECT=reject
                        "EXPECT_MESSAGE=sse4\\.1|popcnt")
  endif()
  if(avx512emu IN_LIST LANES_BUILT_ISAS)
    lanes_qemu_cli_test(qemu.Haswell.avx512emu Haswell ENV_ISA=avx512emu)
  endif()
  lanes_qemu_cli_test(qemu.Haswell.max_avx Haswell ENV_MAX=avx)
endif()

# The kernel tests on each model: each must test exactly the sets that CPU
# runs and skip the others.
#
# qemu 7.2 does not suppress faults of masked-off lanes in vmaskmovps, as
# real CPUs do: a masked load of one float before an inaccessible page dies
# of SIGSEGV under qemu. test_simd_ops checks exactly
# that, so on AVX models it runs only where a probe shows qemu gets it right
# (a later qemu), and otherwise reports itself skipped, naming the reason.
if(LANES_QEMU_X86_64 AND TARGET test_simd_ops)
  file(WRITE ${CMAKE_CURRENT_BINARY_DIR}/qemu_maskload_probe.c [=[
/* Generated by tests/system.cmake: exits 0 when a masked load whose
 * inactive lanes lie on an inaccessible page does not fault. Inline assembly:
 * a compiler turns a one-lane masked load with a constant mask into a plain
 * scalar load, and no -mavx is needed. */
#define _DEFAULT_SOURCE
#include <sys/mman.h>
#include <unistd.h>

int main(void)
{
    long page = sysconf(_SC_PAGESIZE);
    char *mem = mmap(NULL, 2 * (size_t)page, PROT_READ | PROT_WRITE,
                     MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (mem == MAP_FAILED || mprotect(mem + page, (size_t)page, PROT_NONE) != 0) return 2;
    float *last = (float *)(void *)(mem + page) - 1;
    int mask[8] = {-1, 0, 0, 0, 0, 0, 0, 0};
    float got = 0.0f;
    *last = 3.0f;
    __asm__ volatile("vmovdqu (%[mask]), %%ymm1\n\t"
                     "vmaskmovps (%[p]), %%ymm1, %%ymm0\n\t"
                     "vmovss %%xmm0, (%[got])\n\t"
                     "vzeroupper"
                     :
                     : [mask] "r"(mask), [p] "r"(last), [got] "r"(&got)
                     : "xmm0", "xmm1", "memory");
    return got == 3.0f ? 0 : 1;
}
]=])
  add_executable(lanes_qemu_maskload_probe ${CMAKE_CURRENT_BINARY_DIR}/qemu_maskload_probe.c)
endif()

# qemu 7.2 also reads a gather's index register ymm4/xmm4 as "no index" (the
# meaning of index 4 in an ordinary SIB byte, not in a VSIB one), so every
# lane loads base[0]; ymm12 and the other registers work. Whether a kernel set meets this depends on the compiler's
# register allocation (gcc 12 happens not to, clang 14 does). Where the probe
# fails, check_run_sets.cmake leaves out of the qemu run exactly the sets
# whose objects hold such a gather; they are still tested natively.
if(LANES_QEMU_X86_64 AND TARGET test_kernels)
  file(WRITE ${CMAKE_CURRENT_BINARY_DIR}/qemu_vsib_probe.c [=[
/* Generated by tests/system.cmake: exits 0 when vgatherdps with the index in
 * ymm4 loads what the indices say. Inline assembly: no -mavx2 needed. */
int main(void)
{
    float base[8] = {10, 11, 12, 13, 14, 15, 16, 17}, out[8];
    int idx[8] = {7, 6, 5, 4, 3, 2, 1, 0};
    __asm__ volatile("vmovdqu (%[idx]), %%ymm4\n\t"
                     "vpcmpeqd %%ymm1, %%ymm1, %%ymm1\n\t"
                     "vxorps %%ymm2, %%ymm2, %%ymm2\n\t"
                     "vgatherdps %%ymm1, (%[base],%%ymm4,4), %%ymm2\n\t"
                     "vmovups %%ymm2, (%[out])\n\t"
                     "vzeroupper"
                     :
                     : [idx] "r"(idx), [base] "r"(base), [out] "r"(out)
                     : "xmm1", "xmm2", "xmm4", "memory");
    for (int i = 0; i < 8; i++)
        if (out[i] != base[7 - i]) return 1;
    return 0;
}
]=])
  add_executable(lanes_qemu_vsib_probe ${CMAKE_CURRENT_BINARY_DIR}/qemu_vsib_probe.c)
endif()

foreach(binary IN ITEMS test_kernels test_simd_ops)
  if(NOT TARGET ${binary})
    continue()
  endif()
  set(args "")
  if(binary STREQUAL "test_kernels")
    set(args --quick) # 10^4 cases: qemu's TCG is many times slower
  endif()
  foreach(model IN ITEMS core2duo Nehalem SandyBridge Haswell)
    set(name qemu.${model}.${binary})
    if(LANES_QEMU_X86_64)
      set(probe "")
      if(binary STREQUAL "test_simd_ops" AND model MATCHES "SandyBridge|Haswell")
        set(probe -DPROBE=$<TARGET_FILE:lanes_qemu_maskload_probe>)
      endif()
      if(binary STREQUAL "test_kernels" AND model STREQUAL "Haswell")
        list(APPEND probe -DVSIB_PROBE=$<TARGET_FILE:lanes_qemu_vsib_probe>)
        foreach(isa IN ITEMS avx2 avx512emu)
          if(isa IN_LIST LANES_BUILT_ISAS)
            list(APPEND probe
                 "-DOBJECTS_${isa}=$<JOIN:$<TARGET_OBJECTS:lanes_kernels_${isa}>,|>")
          endif()
        endforeach()
      endif()
      add_test(NAME ${name}
        COMMAND ${CMAKE_COMMAND} -DQEMU=${LANES_QEMU_X86_64} "-DQEMU_CPU=${lanes_qemu_cpu_${model}}"
                -DFEATURES=${lanes_qemu_features_${model}} -DCOMPILED=${lanes_compiled_csv}
                -DBINARY=$<TARGET_FILE:${binary}> -DARGS=${args} -DCHECK_SETS=ON ${probe}
                -P ${CMAKE_CURRENT_SOURCE_DIR}/check_run_sets.cmake)
      set_tests_properties(${name} PROPERTIES LABELS qemu TIMEOUT 600
        SKIP_REGULAR_EXPRESSION "SKIP: qemu cannot"
        ENVIRONMENT_MODIFICATION "${LANES_TEST_ENV}")
    else()
      lanes_qemu_skip(${name})
    endif()
  endforeach()
endforeach()
