# SPDX-License-Identifier: BSD-3-Clause
# CTest package.consumer (tests/CMakeLists.txt): install the build to a temporary prefix, configure
# and build tests/consumer against it twice (find_package(ukdyn 0.1 CONFIG REQUIRED), then with
# COMPONENTS static), and run its programs, which check a simulated pendulum against analysis.
#
#   cmake -DBUILD_DIR=... -DCONSUMER_DIR=... -DWORK_DIR=... -DGENERATOR=... -DCXX=...
#         [-DLAUNCHER=ccache] -P run.cmake
cmake_minimum_required(VERSION 3.25)  # the policies of today (CMP0054: quoted arguments)
include(${CMAKE_CURRENT_LIST_DIR}/../packaging/common.cmake)
require(run.cmake BUILD_DIR CONSUMER_DIR WORK_DIR GENERATOR CXX)

file(REMOVE_RECURSE ${WORK_DIR})
set(prefix ${WORK_DIR}/prefix)

run(install ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})
foreach(f ukdynConfig.cmake ukdynConfigVersion.cmake ukdynTargets.cmake ukdynStaticTargets.cmake)
  file(GLOB_RECURSE found ${prefix}/*/${f})
  if(NOT found)
    message(FATAL_ERROR "the install has no ${f}")
  endif()
endforeach()

set(launcher)
if(LAUNCHER)
  set(launcher -DCMAKE_CXX_COMPILER_LAUNCHER=${LAUNCHER})
endif()
foreach(kind shared static)
  set(build ${WORK_DIR}/build-${kind})
  set(want_static OFF)
  if(kind STREQUAL "static")
    set(want_static ON)
  endif()
  run(configure-${kind} ${CMAKE_COMMAND} -S ${CONSUMER_DIR} -B ${build} -G ${GENERATOR}
      -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=${CXX} ${launcher}
      -DCMAKE_PREFIX_PATH=${prefix} -DCONSUMER_STATIC=${want_static})
  run(build-${kind} ${CMAKE_COMMAND} --build ${build})
  run(ldd-${kind} ldd ${build}/consumer_${kind})
  if(last_output MATCHES "not found")
    message(FATAL_ERROR "consumer_${kind}: a library is not found")
  endif()
  if(kind STREQUAL "shared")
    # the installed libukdyn.so, not the build tree's
    string(REGEX MATCH "libukdyn\\.so[^\n]*=> ([^ \n]*)" _ "${last_output}")
    if(NOT CMAKE_MATCH_1 MATCHES "^${prefix}/")
      message(FATAL_ERROR "consumer_shared loads libukdyn from '${CMAKE_MATCH_1}', not from ${prefix}")
    endif()
  elseif(last_output MATCHES "libukdyn")
    message(FATAL_ERROR "consumer_static loads libukdyn.so")
  endif()
  run(consumer-${kind} ${build}/consumer_${kind})
endforeach()
message("package.consumer: ok")
