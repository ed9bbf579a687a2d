# Smoke test of the main job's benchmark: `lanes bench kernels --quick --csv`
# must exit 0 and write a row for every set this CPU runs, each naming the
# resource that bounds it where the bound could be modelled.
#
#   cmake -DCLI=<lanes> -DCSV=<file> -P check_bench.cmake
#
# Only that it runs and reports each set: the timings themselves vary from run
# to run and are the study's business, not a test's.
cmake_minimum_required(VERSION 3.25)

function(fail text)
  message(FATAL_ERROR "FAIL: ${text}")
endfunction()

# LANES_DISABLE_CPU_FEATURES stays: a run that simulates a CPU with less.
foreach(var LANES_ISA LANES_MAX_ISA)
  unset(ENV{${var}})
endforeach()

execute_process(COMMAND "${CLI}" info --json
  RESULT_VARIABLE status OUTPUT_VARIABLE info ERROR_VARIABLE err)
if(NOT status EQUAL 0)
  fail("lanes info --json: exit status ${status}: ${err}")
endif()
string(JSON n LENGTH "${info}" supported)
set(supported "")
math(EXPR last "${n} - 1")
foreach(i RANGE 0 ${last})
  string(JSON isa GET "${info}" supported ${i})
  list(APPEND supported ${isa})
endforeach()

file(REMOVE "${CSV}")
message("run: ${CLI} bench kernels --quick --csv ${CSV}")
execute_process(COMMAND "${CLI}" bench kernels --quick --csv "${CSV}"
  RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
message("${out}${err}")
if(NOT status EQUAL 0)
  fail("exit status ${status}")
endif()
if(NOT EXISTS "${CSV}")
  fail("no CSV written")
endif()

file(STRINGS "${CSV}" rows)
list(POP_FRONT rows header)
string(REPLACE "," ";" columns "${header}")
list(FIND columns isa isa_column)
if(isa_column LESS 0)
  fail("the CSV header has no isa column: ${header}")
endif()
list(FIND columns bound_resource resource_column)
if(resource_column LESS 0)
  fail("the CSV header has no bound_resource column: ${header}")
endif()
set(resources issue mul add mul+add vector load store maskstore)
set(seen "")
set(named 0)
foreach(row IN LISTS rows)
  string(REPLACE "," ";" cells "${row}")
  list(GET cells ${isa_column} isa)
  list(APPEND seen ${isa})
  list(GET cells ${resource_column} resource)
  if(NOT resource STREQUAL "")
    if(NOT resource IN_LIST resources)
      fail("row '${row}': bound_resource '${resource}' is none of ${resources}")
    endif()
    math(EXPR named "${named} + 1")
  endif()
endforeach()
# Empty only where the output says why (no instruction counts, no AVX).
if(named EQUAL 0 AND NOT out MATCHES "UNAVAILABLE")
  fail("no row names the resource that bounds it, and the output says not why")
endif()
foreach(isa IN LISTS supported)
  if(NOT isa IN_LIST seen)
    fail("no CSV row for supported set '${isa}'")
  endif()
endforeach()
list(LENGTH rows count)
string(REPLACE ";" "," supported "${supported}")
message("PASS: ${count} rows covering ${supported}")
