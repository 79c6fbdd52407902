# SPDX-License-Identifier: BSD-3-Clause
# cmake --install BUILD --prefix P (docs/install.md):
#   P/include/ukdyn/...                       the public headers
#   P/lib/libukdyn.so.0.1.0 (+ .so.0.1, .so)  ukdyn::ukdyn, the shared library
#   P/lib/libukdyn.a                          ukdyn::ukdyn_static
#   P/lib/ukdyn/reference/*.o                 ukdyn::reference: the textbook engine's objects
#   P/lib/cmake/ukdyn/                        ukdynConfig.cmake, ukdynConfigVersion.cmake,
#                                             ukdynTargets.cmake, ukdynStaticTargets.cmake
#   P/bin/ukdyn                               the command
#   P/lib/python3/dist-packages/ukdyn/        the Python module (UKDYN_INSTALL_PYTHONDIR)
#   P/share/doc/ukdyn/copyright               the licence (BSD-3-Clause; Debian's format)
#   P/share/licenses/ukdyn/LICENSE            the same, as the C++ package's licence file
include(CMakePackageConfigHelpers)

set(UKDYN_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/ukdyn CACHE STRING
    "Where the CMake package (ukdynConfig.cmake) is installed, relative to the prefix")

install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/ukdyn TYPE INCLUDE FILES_MATCHING PATTERN "*.hpp")

# two export sets: the shared library and the reference objects need only Eigen of their
# consumers; the static library also needs every library it calls (SUNDIALS, yaml-cpp, GiNaC,
# HDF5, SuiteSparse), found only when the `static` component is asked for (ukdynConfig.cmake.in)
install(TARGETS ukdyn EXPORT ukdynTargets LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(TARGETS ukdyn_reference EXPORT ukdynTargets
        OBJECTS DESTINATION ${CMAKE_INSTALL_LIBDIR}/ukdyn/reference)
install(TARGETS ukdyn_static EXPORT ukdynStaticTargets ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(EXPORT ukdynTargets NAMESPACE ukdyn:: DESTINATION ${UKDYN_INSTALL_CMAKEDIR})
install(EXPORT ukdynStaticTargets NAMESPACE ukdyn:: DESTINATION ${UKDYN_INSTALL_CMAKEDIR})

configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/ukdynConfig.cmake.in
  ${PROJECT_BINARY_DIR}/ukdynConfig.cmake INSTALL_DESTINATION ${UKDYN_INSTALL_CMAKEDIR})
# before 1.0 a minor version may break the API: find_package(ukdyn 0.1) accepts 0.1.x only
write_basic_package_version_file(${PROJECT_BINARY_DIR}/ukdynConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/ukdynConfig.cmake ${PROJECT_BINARY_DIR}/ukdynConfigVersion.cmake
              ${CMAKE_CURRENT_LIST_DIR}/ukdynSuiteSparse.cmake
              ${CMAKE_CURRENT_LIST_DIR}/ukdynSiconos.cmake
        DESTINATION ${UKDYN_INSTALL_CMAKEDIR})

# the licence: Debian's machine-readable copyright file where a .deb keeps it, and LICENSE beside
# the CMake package's other shared files
install(FILES ${CMAKE_CURRENT_LIST_DIR}/copyright DESTINATION ${CMAKE_INSTALL_DATAROOTDIR}/doc/ukdyn)
install(FILES ${PROJECT_SOURCE_DIR}/LICENSE DESTINATION ${CMAKE_INSTALL_DATAROOTDIR}/licenses/ukdyn)

# the command links the static library: no run-time path to set, nothing to find
install(TARGETS ukdyn_cli RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
# its man page (help2man, app/CMakeLists.txt) and bash completion (app/completion.bash)
if(UKDYN_MAN_PAGE)
  install(FILES ${UKDYN_MAN_PAGE} DESTINATION ${CMAKE_INSTALL_MANDIR}/man1)
endif()
install(FILES ${PROJECT_SOURCE_DIR}/app/completion.bash RENAME ukdyn
        DESTINATION ${CMAKE_INSTALL_DATAROOTDIR}/bash-completion/completions)
# the documentation and examples, where Debian keeps a package's (/usr/share/doc/ukdyn), with the
# changelog compressed as Debian wants it (gzip -9n: no name, no time stamp)
set(UKDYN_CHANGELOG_GZ ${PROJECT_BINARY_DIR}/debian/changelog.gz)
set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${CMAKE_CURRENT_LIST_DIR}/debian/changelog)
file(MAKE_DIRECTORY ${PROJECT_BINARY_DIR}/debian)
execute_process(COMMAND gzip -9n -c ${CMAKE_CURRENT_LIST_DIR}/debian/changelog
                OUTPUT_FILE ${UKDYN_CHANGELOG_GZ} RESULT_VARIABLE ukdyn_gzip)
if(NOT ukdyn_gzip EQUAL 0)
  message(FATAL_ERROR "gzip of cmake/debian/changelog failed")
endif()
set(UKDYN_DOCDIR ${CMAKE_INSTALL_DATAROOTDIR}/doc/ukdyn)
install(FILES ${UKDYN_CHANGELOG_GZ} ${PROJECT_SOURCE_DIR}/README.md DESTINATION ${UKDYN_DOCDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/docs/ DESTINATION ${UKDYN_DOCDIR}/docs)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/examples/ DESTINATION ${UKDYN_DOCDIR}/examples
        PATTERN "CMakeLists.txt" EXCLUDE PATTERN "__pycache__" EXCLUDE PATTERN "*.pyc" EXCLUDE)
install(FILES ${CMAKE_CURRENT_LIST_DIR}/debian/lintian-overrides RENAME ukdyn
        DESTINATION ${CMAKE_INSTALL_DATAROOTDIR}/lintian/overrides)

if(UKDYN_BUILD_PYTHON)
  # Debian's layout: /usr/lib/python3/dist-packages is on /usr/bin/python3's path; for another
  # prefix, PYTHONPATH=P/lib/python3/dist-packages. The extension links the static library, so
  # the package is self-contained.
  set(UKDYN_INSTALL_PYTHONDIR lib/python3/dist-packages CACHE STRING
      "Where the Python package ukdyn/ is installed, relative to the prefix")
  install(TARGETS ukdyn_python LIBRARY DESTINATION ${UKDYN_INSTALL_PYTHONDIR}/ukdyn)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/python/ukdyn/ DESTINATION ${UKDYN_INSTALL_PYTHONDIR}/ukdyn
          FILES_MATCHING PATTERN "*.py" PATTERN "*.pyi" PATTERN "py.typed" PATTERN "*.html" PATTERN "*.js" PATTERN "__pycache__" EXCLUDE)
endif()
