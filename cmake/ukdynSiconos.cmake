# SPDX-License-Identifier: BSD-3-Clause
# Siconos Numerics, the LCP solver of unilateral contacts (src/dynamics/contact_lcp.cpp,
# docs/contact.md), as the imported target Siconos::numerics. Found by hand: Debian 12's
# libsiconos-numerics-dev ships siconos-config.cmake, but that file requires /usr/bin/siconos and
# the kernel, mechanics and io libraries (other packages) and sets CMAKE_CXX_STANDARD 11 for its
# caller. Used by the build and, installed beside ukdynConfig.cmake, by the consumers of the
# static library (whose link needs it).
find_path(SICONOS_NUMERICS_INCLUDE_DIR siconos/numerics/LinearComplementarityProblem.h REQUIRED)
find_library(SICONOS_NUMERICS_LIBRARY siconos_numerics REQUIRED)
if(NOT TARGET Siconos::numerics)
  add_library(Siconos::numerics UNKNOWN IMPORTED)
  set_target_properties(Siconos::numerics PROPERTIES
    IMPORTED_LOCATION "${SICONOS_NUMERICS_LIBRARY}"
    # (its headers include SiconosConfig.h from siconos/ and each other from siconos/numerics/)
    INTERFACE_INCLUDE_DIRECTORIES
      "${SICONOS_NUMERICS_INCLUDE_DIR};${SICONOS_NUMERICS_INCLUDE_DIR}/siconos;${SICONOS_NUMERICS_INCLUDE_DIR}/siconos/numerics")
endif()
