# Builds and runs tests/consumer against lanes as an outside project would.
#
#   cmake -DMODE=installed -DBUILD=<lanes build> -DWORK=<dir> -DLIBDIR=lib
#         -DCC=<compiler> -P check_consumer.cmake
#       `cmake --install` into WORK/prefix, then the consumer with
#       find_package(lanes) (shared and static) and with pkg-config, and
#       tests/simd_consumer (its own kernel at every set, dispatched);
#   cmake -DMODE=subdirectory -DSOURCE=<lanes source> -DWORK=<dir> -P ...
#       the consumer with add_subdirectory(lanes), library only.
# Fails on any configure, build or run error; the consumer itself checks
# its hits against brute force and prints "N passed, N failed".
cmake_minimum_required(VERSION 3.25)

function(fail text)
  message(FATAL_ERROR "FAIL: ${text}")
endfunction()

# Runs a command, shows it and its output, fails unless it exits 0.
function(run)
  string(REPLACE ";" " " shown "${ARGN}")
  message("run: ${shown}")
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message("${out}${err}")
  if(NOT status EQUAL 0)
    fail("`${shown}` exited with ${status}")
  endif()
  set(run_output "${out}" PARENT_SCOPE)
endfunction()

set(consumer_dir ${CMAKE_CURRENT_LIST_DIR}/consumer)

# What the consumer's own compile line got from lanes: only the include
# directory of <lanes/lanes.h>, none of the project's flags, no source-tree
# include path other than include/.
function(check_compile_line build_dir)
  file(READ ${build_dir}/compile_commands.json commands)
  string(REGEX MATCH "\"command\": \"[^\"]*consumer\\.c[^\"]*\"" line "${commands}")
  if(NOT line)
    fail("no compile command for consumer.c in ${build_dir}/compile_commands.json")
  endif()
  message("consumer.c compiled with: ${line}")
  foreach(leak -ffp-contract -fno-tree-slp-vectorize "-I${SOURCE} " "-I${SOURCE}/simd")
    string(FIND "${line}" "${leak}" at)
    if(NOT at EQUAL -1)
      fail("the consumer inherited '${leak}' from lanes")
    endif()
  endforeach()
endfunction()
# The consumer must not inherit the caller's choice of set, whatever it is.
unset(ENV{LANES_ISA})
unset(ENV{LANES_MAX_ISA})

if(MODE STREQUAL "installed")
  set(prefix ${WORK}/prefix)
  file(REMOVE_RECURSE ${WORK})
  run(${CMAKE_COMMAND} --install ${BUILD} --prefix ${prefix})
  foreach(f include/lanes/lanes.h ${LIBDIR}/liblanes.a ${LIBDIR}/liblanes.so
            ${LIBDIR}/cmake/lanes/lanesConfig.cmake ${LIBDIR}/cmake/lanes/lanesConfigVersion.cmake
            ${LIBDIR}/cmake/lanes/lanesTargets.cmake ${LIBDIR}/pkgconfig/lanes.pc)
    if(NOT EXISTS ${prefix}/${f})
      fail("the install has no ${f}")
    endif()
  endforeach()

  # find_package(lanes): the shared and the static library.
  run(${CMAKE_COMMAND} -S ${consumer_dir} -B ${WORK}/find_package -DCMAKE_PREFIX_PATH=${prefix}
      -DCMAKE_C_COMPILER=${CC} -DCMAKE_EXPORT_COMPILE_COMMANDS=ON)
  run(${CMAKE_COMMAND} --build ${WORK}/find_package)
  check_compile_line(${WORK}/find_package)
  run(${WORK}/find_package/consumer)
  run(${WORK}/find_package/consumer_static)

  # pkg-config, with the compiler alone; the flags it gives must be only the
  # include directory and the library.
  set(ENV{PKG_CONFIG_PATH} ${prefix}/${LIBDIR}/pkgconfig)
  run(pkg-config --cflags --libs lanes)
  string(STRIP "${run_output}" flags)
  if(flags MATCHES "-W|-f|-D")
    fail("pkg-config hands the consumer compile flags: ${flags}")
  endif()
  separate_arguments(flags UNIX_COMMAND "${flags}")
  run(${CC} -std=c11 -Wall -Wextra -Werror -Wpedantic ${consumer_dir}/consumer.c ${flags} -lm
      -o ${WORK}/consumer_pkgconfig)
  set(ENV{LD_LIBRARY_PATH} ${prefix}/${LIBDIR})
  run(${WORK}/consumer_pkgconfig)
  unset(ENV{LD_LIBRARY_PATH})

  # The SIMD layer: a kernel of the consumer's own at every set, dispatched.
  run(${CMAKE_COMMAND} -S ${CMAKE_CURRENT_LIST_DIR}/simd_consumer -B ${WORK}/simd
      -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_C_COMPILER=${CC})
  run(${CMAKE_COMMAND} --build ${WORK}/simd -j2)
  run(${WORK}/simd/simd_consumer)
elseif(MODE STREQUAL "subdirectory")
  file(REMOVE_RECURSE ${WORK})
  run(${CMAKE_COMMAND} -S ${consumer_dir} -B ${WORK} -DLANES_SOURCE_DIR=${SOURCE}
      -DCMAKE_C_COMPILER=${CC} -DCMAKE_EXPORT_COMPILE_COMMANDS=ON)
  run(${CMAKE_COMMAND} --build ${WORK} -j2)
  check_compile_line(${WORK})
  # lanes picks Release only as the top project; the consumer set none
  file(STRINGS ${WORK}/CMakeCache.txt build_type REGEX "^CMAKE_BUILD_TYPE:")
  if(NOT build_type STREQUAL "CMAKE_BUILD_TYPE:STRING=")
    fail("add_subdirectory(lanes) changed the consumer's build type: ${build_type}")
  endif()
  run(${WORK}/consumer)
  run(${WORK}/consumer_static)
else()
  fail("MODE must be installed or subdirectory, not '${MODE}'")
endif()
message("PASS")
