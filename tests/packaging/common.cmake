# SPDX-License-Identifier: BSD-3-Clause
# Shared by the packaging tests' scripts (consumer/run.cmake, packaging/deb.cmake, pip.cmake).

# require(SCRIPT VAR...): fails when one of the -DVAR=... is missing
function(require script)
  foreach(var ${ARGN})
    if(NOT DEFINED ${var})
      message(FATAL_ERROR "${script}: -D${var}=... is required")
    endif()
  endforeach()
endfunction()

# run(STEP COMMAND...): runs the command, prints its output, fails the test on a non-zero exit;
# its output is left in last_output
function(run step)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  message("--- ${step}: ${ARGN}\n${out}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${step} failed (exit ${rc})")
  endif()
  set(last_output "${out}" PARENT_SCOPE)
endfunction()
