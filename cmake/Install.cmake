# `cmake --install <build> --prefix P`: the public header, the static and
# shared libraries, the CMake package (lanes::lanes, the shared library, and
# lanes::lanes_static) and lanes.pc for pkg-config. Included from the
# top-level CMakeLists.txt; the CLI is installed by bench/CMakeLists.txt.
include(CMakePackageConfigHelpers)

set(LANES_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/lanes)

install(TARGETS lanes lanes_shared lanes_simd EXPORT lanesTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(FILES ${PROJECT_SOURCE_DIR}/include/lanes/lanes.h
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/lanes)
# The SIMD layer (lanes::simd) and the helper that compiles a project's own
# sources once per kernel set (lanes_add_kernel_sets, in LanesIsa.cmake).
# simd/isa.h is internal (CPU features); every other header there is public.
# CONFIGURE_DEPENDS: a new backend header is installed without a fresh configure.
file(GLOB lanes_simd_backends CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/simd/vec*.h)
install(FILES ${PROJECT_SOURCE_DIR}/simd/simd.h ${PROJECT_SOURCE_DIR}/simd/kernel_sets.h
              ${PROJECT_SOURCE_DIR}/simd/vmath.h ${PROJECT_SOURCE_DIR}/simd/vrandom.h
              ${PROJECT_SOURCE_DIR}/simd/counter_random.h
              ${lanes_simd_backends}
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/lanes/simd)
install(FILES ${PROJECT_SOURCE_DIR}/cmake/LanesIsa.cmake DESTINATION ${LANES_INSTALL_CMAKEDIR})
install(EXPORT lanesTargets NAMESPACE lanes:: DESTINATION ${LANES_INSTALL_CMAKEDIR})

configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/lanesConfig.cmake.in
  ${PROJECT_BINARY_DIR}/lanesConfig.cmake INSTALL_DESTINATION ${LANES_INSTALL_CMAKEDIR}
  PATH_VARS CMAKE_INSTALL_INCLUDEDIR)
# 0.x: a minor version may change the API.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/lanesConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/lanesConfig.cmake ${PROJECT_BINARY_DIR}/lanesConfigVersion.cmake
        DESTINATION ${LANES_INSTALL_CMAKEDIR})

# pkg-config: `pkg-config --cflags --libs lanes` links the shared library;
# `--static` adds what the static one needs.
# The prefix is found from the .pc file's own place, so the package can be
# installed with any --prefix (chosen at install time, not at configure).
file(RELATIVE_PATH LANES_PC_TO_PREFIX /p/${CMAKE_INSTALL_LIBDIR}/pkgconfig /p)
configure_file(${PROJECT_SOURCE_DIR}/cmake/lanes.pc.in ${PROJECT_BINARY_DIR}/lanes.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/lanes.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
