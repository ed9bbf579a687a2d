# Runs a test binary under qemu-x86_64 with a CPU model (or, without QEMU, on
# this CPU as the oracle sees it) and checks that it passed and that it ran
# exactly the kernel sets that CPU can run.
#
#   cmake -DQEMU=<qemu-x86_64> -DQEMU_CPU=<model> -DFEATURES=<the model's
#         features> -DCOMPILED=<sets> -DBINARY=<test> [-DARGS=a,b]
#         [-DCHECK_SETS=ON] [-DPROBE=<program>]
#         [-DVSIB_PROBE=<program> -DOBJECTS_<set>=<obj>|<obj>...]
#         -P check_run_sets.cmake
#
# PROBE: a program that exits 0 when this qemu handles what the test needs;
# otherwise the test prints "SKIP: qemu cannot ..." (SKIP_REGULAR_EXPRESSION).
# VSIB_PROBE: where it fails, the sets whose objects use a gather that this
# qemu gets wrong are left out of the run (--isa), each with the reason.
#
# CHECK_SETS reads the per-set lines the kernel tests print ("PASS <set> ...",
# "FAIL <set> ...", "SKIP <set>: ..."): a set the model runs must have been
# tested, and a set it cannot run must have been skipped, not attempted.
# Otherwise a detector that wrongly said "no" would leave the test green while
# testing nothing.
cmake_minimum_required(VERSION 3.25)

include(${CMAKE_CURRENT_LIST_DIR}/check_oracle.cmake)

lanes_oracle_environment()

# A known emulator defect the test would trip over: skip, and say which.
if(PROBE)
  execute_process(COMMAND "${QEMU}" -cpu "${QEMU_CPU}" "${PROBE}"
    RESULT_VARIABLE probe_status OUTPUT_QUIET ERROR_QUIET)
  if(NOT probe_status STREQUAL "0")
    message("SKIP: qemu cannot run this test on ${QEMU_CPU}: a masked load (vmaskmovps) "
            "faults on its inactive lanes past the end of a page (probe: ${probe_status}); "
            "real CPUs suppress that fault, and the test checks exactly that")
    return()
  endif()
  message("probe: this qemu suppresses faults of masked-off lanes")
endif()

# qemu's VSIB defect (see system.cmake): leave out the sets whose objects
# hold a gather indexed by ymm4/xmm4, and say so.
set(excluded "")
if(VSIB_PROBE)
  execute_process(COMMAND "${QEMU}" -cpu "${QEMU_CPU}" "${VSIB_PROBE}"
    RESULT_VARIABLE probe_status OUTPUT_QUIET ERROR_QUIET)
  if(NOT probe_status STREQUAL "0")
    foreach(isa IN LISTS expect_supported)
      if(NOT DEFINED OBJECTS_${isa})
        continue()
      endif()
      string(REPLACE "|" ";" objects "${OBJECTS_${isa}}")
      execute_process(COMMAND objdump -d --no-show-raw-insn ${objects}
        RESULT_VARIABLE objdump_status OUTPUT_VARIABLE disassembly ERROR_VARIABLE objdump_err)
      if(NOT objdump_status EQUAL 0)
        fail("objdump on the ${isa} objects: ${objdump_err}")
      endif()
      string(REGEX MATCH "gather[a-z]*[ \t]+[^\n]*,%[xy]mm4,[^\n]*" hit "${disassembly}")
      if(hit)
        list(APPEND excluded ${isa})
        message("not run under qemu: '${isa}': its objects hold `${hit}`, and this qemu reads a "
                "gather index in ymm4/xmm4 as no index (probe: ${probe_status}); the set is "
                "tested natively")
      endif()
    endforeach()
  endif()
endif()

string(REPLACE "," ";" args "${ARGS}")
if(excluded)
  set(run_sets "${expect_supported}")
  list(REMOVE_ITEM run_sets ${excluded})
  list(REMOVE_ITEM expect_supported ${excluded})
  string(REPLACE ";" "," run_sets "${run_sets}")
  list(APPEND args --isa "${run_sets}")
endif()
set(command "${BINARY}" ${args})
set(where "this CPU${simulated}")
if(QEMU)
  list(PREPEND command "${QEMU}" -cpu "${QEMU_CPU}")
  set(where "${QEMU_CPU}")
endif()
string(REPLACE ";" " " shown "${command}")
message("run: ${shown}")
execute_process(COMMAND ${command} RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
message("${out}")
if(NOT err STREQUAL "")
  message("stderr: ${err}")
endif()

set(problems "")
if(CHECK_SETS)
  set(ran "")
  set(skipped "")
  foreach(isa IN LISTS compiled)
    set(tested FALSE)
    set(was_skipped FALSE)
    if(out MATCHES "(^|\n)(PASS|FAIL) ${isa}( |\n)")
      set(tested TRUE)
      list(APPEND ran ${isa})
    endif()
    if(out MATCHES "(^|\n)SKIP ${isa}:")
      set(was_skipped TRUE)
      list(APPEND skipped ${isa})
    endif()
    if(isa IN_LIST expect_supported)
      if(NOT tested OR was_skipped)
        list(APPEND problems "'${isa}' runs on ${where} but was not (fully) tested")
      endif()
    elseif(isa IN_LIST excluded)
      if(tested)
        list(APPEND problems "'${isa}' was left out, yet tested")
      endif()
    elseif(tested OR NOT was_skipped)
      list(APPEND problems "'${isa}' cannot run on ${where} but was not skipped")
    endif()
  endforeach()
  string(REPLACE ";" "," ran "${ran}")
  string(REPLACE ";" "," skipped "${skipped}")
  message("${where}: tested sets [${ran}], skipped [${skipped}]")
endif()

if(NOT status MATCHES "^[0-9]+$")
  list(APPEND problems "died: ${status}")
elseif(NOT status EQUAL 0)
  list(APPEND problems "exit status ${status}")
endif()
if(problems)
  string(REPLACE ";" "\n  " problems "${problems}")
  fail("\n  ${problems}")
endif()
message("PASS")
