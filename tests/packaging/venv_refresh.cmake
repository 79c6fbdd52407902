# SPDX-License-Identifier: BSD-3-Clause
# CTest package.venv_refresh (tests/CMakeLists.txt): cmake/refresh_venv.cmake, which every build
# of build/ runs, brings the module pip installed into .venv/ up to date with the build tree's (a
# rebuild left .venv importing the older module, under the same version), and leaves a venv of
# another Python, or none, alone. On a made-up tree in WORK_DIR: no compiler, no pip.
#
#   cmake -DSOURCE_DIR=... -DWORK_DIR=... -P venv_refresh.cmake
cmake_minimum_required(VERSION 3.25)
include(${CMAKE_CURRENT_LIST_DIR}/common.cmake)
require(venv_refresh.cmake SOURCE_DIR WORK_DIR)

file(REMOVE_RECURSE ${WORK_DIR})
set(package ${WORK_DIR}/build/python/ukdyn)
set(venv ${WORK_DIR}/tree/.venv/lib/python3.11/site-packages/ukdyn)
set(other ${WORK_DIR}/other/.venv/lib/python3.12/site-packages/ukdyn)
set(so _ukdyn.cpython-311-x86_64-linux-gnu.so)
# the build tree: a new extension, a changed and a new Python file
file(WRITE ${package}/${so} "extension, rebuilt")
file(WRITE ${package}/__init__.py "new init")
file(WRITE ${package}/results.py "same")
file(WRITE ${package}/added.py "a file the build added")
# the venv pip made before the rebuild
file(WRITE ${venv}/${so} "extension, as installed")
file(WRITE ${venv}/__init__.py "old init")
file(WRITE ${venv}/results.py "same")
# a venv whose module is for another Python (its own _ukdyn name)
file(WRITE ${other}/_ukdyn.cpython-312-x86_64-linux-gnu.so "for Python 3.12")
file(WRITE ${other}/__init__.py "its init")

function(check file expected)
  file(READ ${file} text)
  if(NOT text STREQUAL expected)
    message(FATAL_ERROR "package.venv_refresh: ${file} holds '${text}', expected '${expected}'")
  endif()
endfunction()

foreach(tree tree other none)
  run(refresh-${tree} ${CMAKE_COMMAND} -DSOURCE_DIR=${WORK_DIR}/${tree} -DPACKAGE_DIR=${package}
      -P ${SOURCE_DIR}/cmake/refresh_venv.cmake)
endforeach()
check(${venv}/${so} "extension, rebuilt")
check(${venv}/__init__.py "new init")
check(${venv}/added.py "a file the build added")
check(${venv}/results.py "same")
check(${other}/__init__.py "its init")
if(EXISTS ${other}/${so})
  message(FATAL_ERROR "package.venv_refresh: the extension went into a venv of another Python")
endif()
message("package.venv_refresh: ok")
