# The tests' own view of which kernel set a CPU can run, shared by the
# check_*.cmake scripts (include()d, after they have read their -D options).
#
# What each set needs is stated in cmake/LanesIsa.cmake apart from the C
# table simd/isa.c reads, and what the CPU offers comes from /proc/cpuinfo or from the
# emulated model's list (FEATURES), never from the detector under test: a slip
# in the detector or in isa.c shows up as a failure.
#
# Inputs: COMPILED (comma list of the sets the build made), FEATURES (comma
# list; empty: /proc/cpuinfo), ENV_DISABLE (the test's own
# LANES_DISABLE_CPU_FEATURES), and LANES_DISABLE_CPU_FEATURES in the
# environment: a whole run simulating a CPU with less (CI runs the suite so,
# as if the CPU lacked AVX-512, and AVX2). The two lists add up.
# Sets: compiled, features (what the CPU offers), disabled (both switches),
# usable (features after the switches), unknown_disabled (names in the
# switches that are no feature: the program must refuse them), disable_value (what the program under
# test must get as LANES_DISABLE_CPU_FEATURES; empty: unset), feature_source,
# simulated (a note for messages), expect_supported (compiled and runnable),
# lanes_oracle_ok (FALSE: no view of the CPU; the caller skips). Provides
# fail(), runnable() and lanes_oracle_environment() (sets the program's
# LANES_* variables: the test's values and the simulation, nothing else).

# The sets and what each needs: cmake/LanesIsa.cmake, which states the
# needs apart from simd/kernel_sets.h's C column (the detector's view).
include(${CMAKE_CURRENT_LIST_DIR}/../cmake/LanesIsa.cmake)
set(ALL_ISAS ${LANES_ALL_ISAS})
foreach(isa IN LISTS ALL_ISAS)
  set(NEEDS_${isa} ${LANES_ISA_NEEDS_${isa}})
  set(LANES_${isa} ${LANES_ISA_LANES_${isa}})
endforeach()
set(ALL_FEATURES sse2 sse3 ssse3 sse4.1 sse4.2 popcnt osxsave avx f16c fma avx2 bmi1 bmi2
    lzcnt avx512f avx512cd avx512dq avx512bw avx512vl)

function(fail text)
  message(FATAL_ERROR "FAIL: ${text}")
endfunction()

string(REPLACE "," ";" compiled "${COMPILED}")
set(lanes_oracle_ok TRUE)

if(FEATURES)
  string(REPLACE "," ";" features "${FEATURES}")
  set(feature_source "the emulated CPU model")
elseif(EXISTS /proc/cpuinfo)
  file(STRINGS /proc/cpuinfo flags_line REGEX "^flags[ \t]*:" LIMIT_COUNT 1)
  string(REGEX REPLACE "^flags[ \t]*:[ \t]*" "" flags_line "${flags_line}")
  string(REPLACE " " ";" flags "${flags_line}")
  # Linux lists a feature only when the kernel enabled it: with `noxsave` it
  # drops xsave and every AVX flag, which is what the OS-consent check wants.
  # OSXSAVE itself is not listed; xsave stands for it.
  set(cpuinfo_sse3 pni)
  set(cpuinfo_sse4.1 sse4_1)
  set(cpuinfo_sse4.2 sse4_2)
  set(cpuinfo_osxsave xsave)
  set(cpuinfo_lzcnt abm)
  set(features "")
  foreach(f IN LISTS ALL_FEATURES)
    set(name "${f}")
    if(DEFINED cpuinfo_${f})
      set(name "${cpuinfo_${f}}")
    endif()
    if(name IN_LIST flags)
      list(APPEND features ${f})
    endif()
  endforeach()
  set(feature_source "/proc/cpuinfo")
else()
  set(lanes_oracle_ok FALSE)
  set(features "")
  set(feature_source "nothing")
endif()

# The disable switch takes features away from what the detector sees.
set(disable_value "$ENV{LANES_DISABLE_CPU_FEATURES}")
set(simulated "")
if(NOT disable_value STREQUAL "")
  set(simulated " (the run simulates a CPU without ${disable_value})")
endif()
if(NOT "${ENV_DISABLE}" STREQUAL "")
  if(disable_value STREQUAL "")
    set(disable_value "${ENV_DISABLE}")
  else()
    string(APPEND disable_value ",${ENV_DISABLE}")
  endif()
endif()
string(REPLACE "," ";" disabled "${disable_value}")
set(unknown_disabled "")
foreach(f IN LISTS disabled)
  if(NOT f IN_LIST ALL_FEATURES)
    list(APPEND unknown_disabled ${f})
  endif()
endforeach()
set(usable "${features}")
if(disabled)
  list(REMOVE_ITEM usable ${disabled})
endif()

function(runnable isa out)
  set(ok TRUE)
  foreach(f IN LISTS NEEDS_${isa})
    if(NOT f IN_LIST usable)
      set(ok FALSE)
    endif()
  endforeach()
  set(${out} ${ok} PARENT_SCOPE)
endfunction()

set(expect_supported "")
foreach(isa IN LISTS ALL_ISAS)
  runnable(${isa} ok)
  if(ok AND isa IN_LIST compiled)
    list(APPEND expect_supported ${isa})
  endif()
endforeach()

# The environment of the program under test: LANES_ISA and LANES_MAX_ISA as
# the test gives them (else unset), LANES_DISABLE_CPU_FEATURES as both
# switches together.
macro(lanes_oracle_environment)
  foreach(var LANES_ISA LANES_MAX_ISA LANES_DISABLE_CPU_FEATURES)
    unset(ENV{${var}})
  endforeach()
  if(NOT "${ENV_ISA}" STREQUAL "")
    set(ENV{LANES_ISA} "${ENV_ISA}")
  endif()
  if(NOT "${ENV_MAX}" STREQUAL "")
    set(ENV{LANES_MAX_ISA} "${ENV_MAX}")
  endif()
  if(NOT "${disable_value}" STREQUAL "")
    set(ENV{LANES_DISABLE_CPU_FEATURES} "${disable_value}")
  endif()
endmacro()
