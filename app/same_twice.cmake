# SPDX-License-Identifier: BSD-3-Clause
cmake_minimum_required(VERSION 3.25)
# Test driver: runs `UKDYN run --example EXAMPLE -o DIR/1 …` and again into DIR/2, in two
# processes (two address-space layouts), and requires the same trajectory.csv byte for byte.
#   cmake -DUKDYN=path -DEXAMPLE=name -DDIR=dir -P same_twice.cmake
foreach(run 1 2)
  execute_process(COMMAND ${UKDYN} run --example ${EXAMPLE} -o ${DIR}/${run} --t-end 1 --no-plots
                  RESULT_VARIABLE code OUTPUT_QUIET)
  if(NOT code EQUAL 0)
    message(FATAL_ERROR "ukdyn run --example ${EXAMPLE} exited with ${code}")
  endif()
endforeach()
execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files ${DIR}/1/trajectory.csv
                        ${DIR}/2/trajectory.csv RESULT_VARIABLE differ)
if(differ)
  message(FATAL_ERROR "two runs of ${EXAMPLE} wrote different trajectories")
endif()
