# The public API (label "api"): test_api includes only <lanes/lanes.h> and
# links the shared library, as a user's program does. Included from
# tests/CMakeLists.txt.
add_executable(test_api ${CMAKE_CURRENT_LIST_DIR}/test_api.c)
target_link_libraries(test_api PRIVATE lanes::lanes Threads::Threads m)
target_compile_options(test_api PRIVATE -Wall -Wextra $<$<BOOL:${LANES_WERROR}>:-Werror>)
add_test(NAME api.queries COMMAND test_api)
set_tests_properties(api.queries PROPERTIES LABELS api TIMEOUT 600
  ENVIRONMENT_MODIFICATION "${LANES_TEST_ENV}")

# A device asking for a set the CPU lacks is refused with LANES_ERR_CPU_LACKS
# (the switch adds to any simulation the run makes).
if(avx2 IN_LIST LANES_BUILT_ISAS)
  add_test(NAME api.refuse_avx2 COMMAND test_api --expect-refused avx2)
  set_tests_properties(api.refuse_avx2 PROPERTIES LABELS api TIMEOUT 600
    ENVIRONMENT_MODIFICATION "${LANES_TEST_ENV};LANES_DISABLE_CPU_FEATURES=string_append:,avx2")
endif()

# The package as outside projects use it (label "install"): the consumer in
# tests/consumer/ built against `cmake --install` output with find_package
# and with pkg-config, and through add_subdirectory of this source tree.
add_test(NAME install.package
  COMMAND ${CMAKE_COMMAND} -DMODE=installed -DBUILD=${CMAKE_BINARY_DIR}
          -DWORK=${CMAKE_CURRENT_BINARY_DIR}/consumer-installed -DLIBDIR=${CMAKE_INSTALL_LIBDIR}
          -DSOURCE=${PROJECT_SOURCE_DIR}
          -DCC=${CMAKE_C_COMPILER} -P ${CMAKE_CURRENT_SOURCE_DIR}/check_consumer.cmake)
add_test(NAME install.subdirectory
  COMMAND ${CMAKE_COMMAND} -DMODE=subdirectory -DSOURCE=${PROJECT_SOURCE_DIR}
          -DWORK=${CMAKE_CURRENT_BINARY_DIR}/consumer-subdirectory -DCC=${CMAKE_C_COMPILER}
          -P ${CMAKE_CURRENT_SOURCE_DIR}/check_consumer.cmake)
set_tests_properties(install.package install.subdirectory PROPERTIES LABELS install TIMEOUT 900)

# The shared library exports the public API and nothing else.
add_test(NAME install.exports
  COMMAND bash -c "nm -D --defined-only \"$1\" | awk '{print $3}' | sort > \"$2\"; \
                   n=$(wc -l < \"$2\"); bad=$(grep -v '^lanes_' \"$2\"); \
                   echo \"$n exported symbols\"; \
                   if [ -n \"$bad\" ]; then echo \"FAIL: exported without the lanes_ prefix: $bad\"; exit 1; fi; \
                   api=$(grep -c '^LANES_API' \"$3\"); \
                   if [ \"$n\" -ne \"$api\" ]; then echo \"FAIL: $n exported, $api declared LANES_API in lanes.h\"; exit 1; fi; \
                   echo PASS" _
          $<TARGET_FILE:lanes_shared> ${CMAKE_CURRENT_BINARY_DIR}/exports.txt
          ${PROJECT_SOURCE_DIR}/include/lanes/lanes.h)
set_tests_properties(install.exports PROPERTIES LABELS install TIMEOUT 60)
