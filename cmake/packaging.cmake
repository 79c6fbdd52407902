# SPDX-License-Identifier: BSD-3-Clause
# cpack -G DEB (in the build directory, or `cpack --config build/CPackConfig.cmake`):
# ukdyn_<version>_<arch>.deb, everything cmake/install.cmake installs, under /usr. One package
# holds the library (shared and static), headers and CMake package, the command and the Python
# module: the build's own layout, not Debian's split into lib/-dev/python3- packages.
#
# Depends: the shared libraries the ELF files load, by dpkg-shlibdeps (on Debian 12:
# libsundials-cvode6, libyaml-cpp0.7, libginac11, libcln6, libhdf5-103-1, libhdf5-cpp-103-1,
# libcholmod3, libstdc++6, libgcc-s1, libc6; it needs `file` and dpkg-dev), and
# what the Python module imports (python3 of the version it was built for, python3-numpy).
# Recommends: what the plots, DataFrames and Datasets use (the pip extras of pyproject.toml) and
# what C++ consumers need (Eigen's headers and
# CMake package: find_dependency(Eigen3) in ukdynConfig.cmake).
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME ukdyn)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY ${PROJECT_DESCRIPTION})
set(CPACK_RESOURCE_FILE_LICENSE ${PROJECT_SOURCE_DIR}/LICENSE)  # BSD-3-Clause
set(CPACK_PACKAGE_CONTACT "ukdyn maintainers <maintainers@users.noreply.h-seed-56c80d22.example>")
# stripped, as Debian ships binaries (lintian: unstripped-binary-or-object)
set(CPACK_STRIP_FILES ON)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)  # <name>_<version>_<arch>.deb
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_DESCRIPTION
    "Udwadia-Kalaba equations of motion of constrained mechanical systems\n\
 The C++ library (shared and static, headers, CMake package ukdyn), the\n\
 ukdyn command (model files: simulation, checks, plots) and the Python module.")
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
# libukdyn.so.0.1's shlibs file (packages built against it depend on this one) and the ldconfig
# trigger, written here rather than by CPack, whose GENERATE_SHLIBS also adds maintainer scripts
# that call ldconfig (lintian: maintscript-calls-ldconfig; Debian uses the trigger)
file(WRITE ${PROJECT_BINARY_DIR}/debian/shlibs
     "libukdyn ${PROJECT_VERSION_MAJOR}.${PROJECT_VERSION_MINOR} ukdyn (>= ${PROJECT_VERSION})\n")
# (CPack writes postinst and postrm scripts that call ldconfig unless the package brings its own:
# these two do nothing)
foreach(f triggers postinst postrm)
  configure_file(${CMAKE_CURRENT_LIST_DIR}/debian/${f} ${PROJECT_BINARY_DIR}/debian/${f} COPYONLY)
endforeach()
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA ${PROJECT_BINARY_DIR}/debian/shlibs
    ${PROJECT_BINARY_DIR}/debian/triggers ${PROJECT_BINARY_DIR}/debian/postinst
    ${PROJECT_BINARY_DIR}/debian/postrm)
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
set(_ukdyn_depends "")
if(UKDYN_BUILD_PYTHON)
  # the extension is built for one Python (its ABI suffix, e.g. cpython-311): that version only
  math(EXPR _ukdyn_py_next "${UKDYN_PYTHON_VERSION_MINOR} + 1")
  set(_ukdyn_depends "python3 (>= ${UKDYN_PYTHON_VERSION_MAJOR}.${UKDYN_PYTHON_VERSION_MINOR}~), \
python3 (<< ${UKDYN_PYTHON_VERSION_MAJOR}.${_ukdyn_py_next}), python3-numpy, libjs-three")
endif()
set(CPACK_DEBIAN_PACKAGE_DEPENDS "${_ukdyn_depends}")
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS
    "python3-matplotlib, python3-pandas, python3-xarray, libeigen3-dev")
set(CPACK_DEBIAN_PACKAGE_SUGGESTS "python3-sympy, libsundials-dev, libyaml-cpp-dev, libginac-dev, \
libhdf5-dev, libsuitesparse-dev, libsiconos-numerics-dev")
include(CPack)
