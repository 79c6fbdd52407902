# SPDX-License-Identifier: BSD-3-Clause
# CHOLMOD and SuiteSparseQR, the sparse engine's factorizations, as imported targets
# SuiteSparse::cholmod, SuiteSparse::spqr and SuiteSparse::suitesparseconfig (the names
# SuiteSparse 7 gives its own CMake package). SuiteSparse 5, Debian 12's, ships no CMake package,
# so they are found by hand. Used by the build and, installed beside ukdynConfig.cmake, by the
# consumers of the static library (whose link needs them). Sets SUITESPARSE_INCLUDE_DIR.
find_path(SUITESPARSE_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse REQUIRED)
foreach(_ukdyn_ss suitesparseconfig cholmod spqr)
  string(TOUPPER ${_ukdyn_ss} _ukdyn_SS)
  find_library(${_ukdyn_SS}_LIBRARY ${_ukdyn_ss} REQUIRED)
  if(NOT TARGET SuiteSparse::${_ukdyn_ss})
    add_library(SuiteSparse::${_ukdyn_ss} UNKNOWN IMPORTED)
    set_target_properties(SuiteSparse::${_ukdyn_ss} PROPERTIES
      IMPORTED_LOCATION "${${_ukdyn_SS}_LIBRARY}"
      INTERFACE_INCLUDE_DIRECTORIES "${SUITESPARSE_INCLUDE_DIR}")
  endif()
endforeach()
unset(_ukdyn_ss)
unset(_ukdyn_SS)
