# Runs one libFuzzer target for a bounded time (tests/fuzz/fuzz.cmake):
#   cmake -DFUZZER=... -DSEEDS=<repo corpus> -DCORPUS=<build copy>
#         -DARTIFACTS=<dir> -DSECONDS=n [-DDICT=file] -P run_fuzzer.cmake
#
# Limits: an input may take 10 s (-timeout), allocate 1 GiB in one call
# (-malloc_limit_mb) and 2 GiB in all (-rss_limit_mb); beyond that it is a
# hang or an unbounded allocation, reported like a crash.
foreach(v FUZZER SEEDS CORPUS ARTIFACTS SECONDS)
  if(NOT DEFINED ${v})
    message(FATAL_ERROR "run_fuzzer.cmake: -D${v}= missing")
  endif()
endforeach()

# The committed seeds are copied in every time (new seeds arrive; the
# inputs found by earlier runs stay).
file(MAKE_DIRECTORY ${CORPUS} ${ARTIFACTS})
file(GLOB seeds ${SEEDS}/*)
if(NOT seeds)
  message(FATAL_ERROR "run_fuzzer.cmake: no seeds in ${SEEDS}")
endif()
file(COPY ${seeds} DESTINATION ${CORPUS})

set(args -max_total_time=${SECONDS} -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=1024
    -print_final_stats=1 -artifact_prefix=${ARTIFACTS}/)
if(DICT)
  list(APPEND args -dict=${DICT})
endif()
if(SEED)
  list(APPEND args -seed=${SEED})
endif()
# Leaks inside Assimp (C++ allocations) are its own; lsan.supp says why.
set(ENV{LSAN_OPTIONS} "suppressions=${CMAKE_CURRENT_LIST_DIR}/lsan.supp")
message(STATUS "+ LSAN_OPTIONS=$ENV{LSAN_OPTIONS} ${FUZZER} ${args} ${CORPUS}")
execute_process(COMMAND ${FUZZER} ${args} ${CORPUS} RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  file(GLOB found ${ARTIFACTS}/*)
  message(FATAL_ERROR "fuzzer failed (${rc}); inputs saved: ${found}\n"
                      "replay one with: ${FUZZER} <input>")
endif()
