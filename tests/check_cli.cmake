# Runs `lanes info --json` in a given situation and checks which kernel set it
# chose, or that it refused. Run by CTest through tests/system.cmake:
#
#   cmake -DCLI=<lanes> -DCOMPILED=scalar,sse4,... [options] -P check_cli.cmake
#
# Options (all optional):
#   FEATURES     comma list of the CPU features the (emulated) CPU offers, as
#                simd/cpu.c names them; empty: read /proc/cpuinfo
#   QEMU, QEMU_CPU  run the CLI as `<QEMU> -cpu <QEMU_CPU> <lanes> ...`
#   ENV_ISA, ENV_MAX, ENV_DISABLE  values for LANES_ISA, LANES_MAX_ISA,
#                LANES_DISABLE_CPU_FEATURES
#   FLAG_ISA     passed as `--isa <value>`
#   EXPECT       "select" (default): exit 0 with the set computed below (a
#                forced set the CPU cannot run turns it into "reject");
#                "reject": exit status exactly 2, and a message that names a
#                missing feature (or lists the valid names, for a bad name)
#   EXPECT_MESSAGE  a regular expression the output must also match
#
# The expected choice is computed by check_oracle.cmake, independently of the
# detector under test. Prints "SKIP:" (CTest's SKIP_REGULAR_EXPRESSION) when
# the situation cannot arise on this CPU.
cmake_minimum_required(VERSION 3.25)

if(NOT CLI OR NOT EXISTS "${CLI}")
  message(FATAL_ERROR "FAIL: CLI='${CLI}' does not exist")
endif()
if(NOT EXPECT)
  set(EXPECT select)
endif()

include(${CMAKE_CURRENT_LIST_DIR}/check_oracle.cmake)
if(NOT lanes_oracle_ok)
  message("SKIP: no /proc/cpuinfo and no FEATURES given: no independent view of the CPU")
  return()
endif()

# --- what the CLI should do --------------------------------------------------
set(forced "")
if(FLAG_ISA)
  set(forced "${FLAG_ISA}")   # the flag is an API call: it beats the environment
elseif(ENV_ISA)
  set(forced "${ENV_ISA}")
endif()

set(expect_selected "")
if(unknown_disabled)
  set(EXPECT reject) # a typo in the switch must not pass for a CPU without it
endif()
if(EXPECT STREQUAL "select")
  if(forced)
    if(forced IN_LIST expect_supported)
      set(expect_selected "${forced}")
    else()
      # Forcing a set this CPU cannot run is refused: check the refusal.
      string(REPLACE ";" "," u "${usable}")
      message("'${forced}' cannot run here (usable features from ${feature_source}: ${u}; "
              "compiled: ${COMPILED}): expecting a refusal")
      set(EXPECT reject)
    endif()
  else()
    # The best-ranked automatic set at or below the cap's rank.
    set(cap_rank 1000000)
    if(ENV_MAX)
      set(cap_rank ${LANES_ISA_RANK_${ENV_MAX}})
    endif()
    set(expect_selected scalar)
    set(best_rank -1)
    foreach(isa IN LISTS ALL_ISAS)
      if(LANES_ISA_AUTOMATIC_${isa} AND isa IN_LIST expect_supported
         AND NOT LANES_ISA_RANK_${isa} GREATER cap_rank AND LANES_ISA_RANK_${isa} GREATER best_rank)
        set(expect_selected ${isa})
        set(best_rank ${LANES_ISA_RANK_${isa}})
      endif()
    endforeach()
  endif()
elseif(NOT EXPECT STREQUAL "reject")
  fail("EXPECT must be select or reject, not '${EXPECT}'")
endif()

# --- run it ------------------------------------------------------------------
# A LANES_* variable set by whoever runs ctest must not change what this test
# sees, except the simulation of a CPU with less (check_oracle.cmake).
lanes_oracle_environment()

set(command "${CLI}" info --json)
if(NOT "${FLAG_ISA}" STREQUAL "")
  list(APPEND command --isa "${FLAG_ISA}")
endif()
if(QEMU)
  list(PREPEND command "${QEMU}" -cpu "${QEMU_CPU}")
endif()

string(REPLACE ";" " " shown "${command}")
set(shown_env "")
foreach(var LANES_ISA LANES_MAX_ISA LANES_DISABLE_CPU_FEATURES)
  if(DEFINED ENV{${var}})
    string(APPEND shown_env "${var}=$ENV{${var}} ")
  endif()
endforeach()
message("run: ${shown_env}${shown}")

execute_process(COMMAND ${command}
  RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
message("exit status: ${status}")
if(NOT out STREQUAL "")
  message("stdout: ${out}")
endif()
if(NOT err STREQUAL "")
  message("stderr: ${err}")
endif()

# A signal (SIGILL above all) comes back as text, not as a number.
if(NOT status MATCHES "^[0-9]+$")
  fail("the CLI died: ${status}")
endif()

# The features of `features` that `text` names as words (avx is not avx2).
function(named_in features out)
  set(named "")
  foreach(f IN LISTS features)
    string(REPLACE "." "\\." re "${f}")
    if(text MATCHES "(^|[^a-z0-9.])${re}([^a-z0-9.]|$)")
      list(APPEND named ${f})
    endif()
  endforeach()
  set(${out} "${named}" PARENT_SCOPE)
endfunction()

if(EXPECT STREQUAL "reject")
  if(NOT status EQUAL 2)
    fail("expected exit status 2, got ${status}")
  endif()
  set(text "${out}${err}")
  # Set names and feature names overlap (avx, avx2): the message's echo of
  # the requested set must not count as naming the missing feature.
  if(forced)
    foreach(echo IN ITEMS "'${forced}'" "--isa ${forced}" "LANES_ISA=${forced}")
      string(REPLACE "${echo}" "<set>" text "${text}")
    endforeach()
  endif()
  if(EXPECT_MESSAGE AND NOT text MATCHES "${EXPECT_MESSAGE}")
    fail("the message does not match '${EXPECT_MESSAGE}'")
  endif()
  if(unknown_disabled)
    # Refused for the switch's sake, whatever set was asked for.
    list(GET unknown_disabled 0 first)
    if(NOT text MATCHES "LANES_DISABLE_CPU_FEATURES: '${first}' is not a CPU feature")
      fail("the message does not name '${first}' as an unknown feature of the switch")
    endif()
    named_in("${ALL_FEATURES}" listed)
    if(NOT listed STREQUAL ALL_FEATURES)
      fail("the message does not list every valid feature name (lists: ${listed})")
    endif()
  elseif(forced AND NOT forced IN_LIST ALL_ISAS)
    # A name that is no set: the message must list the real ones.
    foreach(isa IN LISTS ALL_ISAS)
      if(NOT text MATCHES "(^|[^a-z0-9])${isa}([^a-z0-9]|$)")
        fail("the message does not list the valid name '${isa}'")
      endif()
    endforeach()
  elseif(forced AND forced IN_LIST compiled)
    # Refused for the CPU's sake: the message gives the first cause a user
    # needs, as the oracle sees it. Features the CPU does not offer (absent
    # from cpuid, or their register state not enabled by the OS: Linux drops
    # both from /proc/cpuinfo alike) come before those the switch hides; the
    # message must name such a feature, and must not blame the switch. Only
    # when the CPU offers everything does the switch explain it, and then
    # every needed feature it hides is named. No feature is named that the
    # set needs and can use. (Which of CPU and OS it blames is checked by
    # test_cpu_explain, on CPU states this machine is not.)
    set(lacked "")
    set(switched "")
    set(available "")
    foreach(f IN LISTS NEEDS_${forced})
      if(NOT f IN_LIST features)
        list(APPEND lacked ${f})
      elseif(NOT f IN_LIST usable)
        list(APPEND switched ${f})
      else()
        list(APPEND available ${f})
      endif()
    endforeach()
    if(NOT lacked AND NOT switched)
      fail("'${forced}' can run here, so refusing it is wrong")
    endif()
    named_in("${available}" wrongly)
    if(wrongly)
      string(REPLACE ";" "," wrongly "${wrongly}")
      fail("the message names features this CPU offers and the set can use: ${wrongly}")
    endif()
    if(lacked)
      named_in("${lacked}" named)
      string(REPLACE ";" "," lacked "${lacked}")
      if(NOT named)
        fail("the message names none of the features the CPU lacks (${lacked})")
      endif()
      if(NOT text MATCHES "this CPU lacks|the OS has not enabled")
        fail("the message does not say the CPU (or its OS) lacks ${lacked}")
      endif()
      if(text MATCHES "LANES_DISABLE_CPU_FEATURES")
        fail("the message blames LANES_DISABLE_CPU_FEATURES, but the CPU lacks ${lacked}")
      endif()
    else()
      named_in("${switched}" named)
      if(NOT named STREQUAL switched)
        string(REPLACE ";" "," switched "${switched}")
        fail("the message does not name every feature the switch hides (${switched})")
      endif()
      if(NOT text MATCHES "LANES_DISABLE_CPU_FEATURES switches off")
        fail("the message does not say that LANES_DISABLE_CPU_FEATURES hides the features")
      endif()
    endif()
    string(REPLACE ";" "," named "${named}")
    message("refused, naming: ${named}${simulated}")
  endif()
  message("PASS: refused with exit status 2")
  return()
endif()

if(NOT status EQUAL 0)
  fail("expected exit status 0, got ${status}")
endif()

string(JSON selected ERROR_VARIABLE json_err GET "${out}" selected)
if(json_err)
  fail("stdout is not the JSON object `lanes info --json` promises: ${json_err}")
endif()
string(JSON lanes ERROR_VARIABLE json_err GET "${out}" lanes)
if(json_err)
  fail("no \"lanes\" key: ${json_err}")
endif()

function(json_list key out_var)
  string(JSON n ERROR_VARIABLE e LENGTH "${out}" ${key})
  if(e)
    fail("no \"${key}\" array: ${e}")
  endif()
  set(items "")
  if(n GREATER 0)
    math(EXPR last "${n} - 1")
    foreach(i RANGE 0 ${last})
      string(JSON item GET "${out}" ${key} ${i})
      list(APPEND items "${item}")
    endforeach()
  endif()
  list(SORT items)
  set(${out_var} "${items}" PARENT_SCOPE)
endfunction()

json_list(compiled got_compiled)
json_list(supported got_supported)
set(want_compiled "${compiled}")
list(SORT want_compiled)
set(want_supported "${expect_supported}")
list(SORT want_supported)

# Lists shown with commas: a ";" would split the messages below.
foreach(v got_compiled want_compiled got_supported want_supported)
  string(REPLACE ";" "," ${v} "${${v}}")
endforeach()
set(problems "")
if(NOT got_compiled STREQUAL want_compiled)
  list(APPEND problems "compiled: got [${got_compiled}], the build made [${want_compiled}]")
endif()
if(NOT got_supported STREQUAL want_supported)
  list(APPEND problems "supported: got [${got_supported}], expected [${want_supported}] from ${feature_source}")
endif()
if(NOT selected STREQUAL expect_selected)
  list(APPEND problems "selected: got '${selected}', expected '${expect_selected}'")
endif()
if(NOT lanes STREQUAL "${LANES_${selected}}")
  list(APPEND problems "lanes: got ${lanes} for '${selected}', expected ${LANES_${selected}}")
endif()
if(problems)
  string(REPLACE ";" "\n  " problems "${problems}")
  fail("\n  ${problems}")
endif()
set(where "")
if(QEMU)
  set(where " under qemu -cpu ${QEMU_CPU}")
endif()
message("PASS: selected ${selected}, lanes ${lanes}${where}")
