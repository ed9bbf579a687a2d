# LANES_SANITIZE: the whole project (library, kernel sets, CLI, tests) built
# with AddressSanitizer and UndefinedBehaviorSanitizer, so that the ordinary
# test suite doubles as a memory-error and UB check:
#
#   cmake -S . -B out-asan -DLANES_SANITIZE=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo
#   cmake --build out-asan -j2 && ctest --test-dir out-asan -j2 --output-on-failure
#
# Included from the top-level CMakeLists.txt before any target exists, so
# add_compile_options reaches every target. The kernel-set probes
# (check_c_source_compiles) do not see these options, which is what we want:
# whether a compiler can build AVX-512 does not depend on the sanitizers.
#
# A fuzz build (LANES_FUZZ, declared in tests/fuzz/fuzz.cmake and read here
# from the cache, because only this early can flags reach every target) is
# a sanitizer build too, with libFuzzer's coverage instrumentation in all C
# code, so the fuzzers see inside the loaders they link.
option(LANES_SANITIZE "Build everything with -fsanitize=address,undefined (a test build)" OFF)

if(LANES_SANITIZE OR LANES_FUZZ)
  if(NOT CMAKE_C_COMPILER_ID MATCHES "GNU|Clang")
    message(FATAL_ERROR "LANES_SANITIZE needs gcc or clang, not ${CMAKE_C_COMPILER_ID}")
  endif()
  if(LANES_FUZZ)
    if(NOT CMAKE_C_COMPILER_ID STREQUAL "Clang")
      message(FATAL_ERROR "LANES_FUZZ needs clang's libFuzzer: configure a fresh build "
                          "directory with CC=clang-14 CXX=clang++-14")
    endif()
    if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
      # gcc's and clang's ASan runtimes do not mix in one program.
      message(WARNING "LANES_FUZZ: the C++ compiler is not clang (set CXX=clang++-14); "
                      "only the fuzz targets (lanes_fuzzers) will link")
    endif()
    add_compile_options($<$<COMPILE_LANGUAGE:C>:-fsanitize=fuzzer-no-link>)
  endif()
  # -fno-sanitize-recover: a UB report fails the test instead of scrolling
  # past in its output. Neither compiler's "undefined" group includes
  # float-divide-by-zero, which the tracer relies on (1/0 = inf in ray
  # reciprocals), so nothing needs to be switched off for that.
  set(LANES_SANITIZE_FLAGS -fsanitize=address,undefined -fno-sanitize-recover=undefined
      -fno-omit-frame-pointer)
  add_compile_options(${LANES_SANITIZE_FLAGS})
  add_link_options(-fsanitize=address,undefined)
  message(STATUS "lanes: sanitizer build (${LANES_SANITIZE_FLAGS})")
endif()

# Called (deferred) at the end of tests/CMakeLists.txt: marks DISABLED the
# tests that cannot mean anything in a sanitizer build, so that ctest lists
# them as "Not Run (Disabled)" with this reason instead of failing.
function(lanes_sanitize_exclude_tests)
  if(NOT LANES_SANITIZE AND NOT LANES_FUZZ)
    return()
  endif()
  get_property(tests DIRECTORY PROPERTY TESTS)
  set(disabled "")
  foreach(t IN LISTS tests)
    get_test_property(${t} LABELS labels)
    # qemu-user cannot run ASan binaries: ASan reserves terabytes of shadow
    # memory, and qemu 7.2 keeps page bookkeeping for the whole guest
    # reservation; `qemu-x86_64 -cpu Haswell out-asan/lanes info` grew to
    # 24 GB resident in 40 s until the OOM killer stopped it.
    if("qemu" IN_LIST labels
       # ASan adds a module constructor (asan.module_ctor, in .init_array) to
       # every instrumented object, which is exactly what this test forbids
       # in kernel objects; the unsanitized builds keep checking it.
       OR t STREQUAL "hygiene.no_constructors"
       # The consumers are built as outside projects are, without the
       # sanitizer's flags, and cannot load an ASan-built liblanes (nor
       # would its exports be only the API: ASan adds symbols of its own).
       OR "install" IN_LIST labels)
      set_tests_properties(${t} PROPERTIES DISABLED TRUE)
      list(APPEND disabled ${t})
    endif()
  endforeach()
  list(LENGTH disabled n)
  message(STATUS "lanes: sanitizer build: ${n} tests disabled (qemu cannot run ASan "
                 "binaries; ASan adds constructors to kernel objects; the install consumers "
                 "are not sanitizer builds)")
endfunction()
