# SPDX-License-Identifier: BSD-3-Clause
cmake_minimum_required(VERSION 3.25)
# The man page ukdyn.1.gz, generated from the command's own --help and --version by help2man
# (run at build time by app/CMakeLists.txt); each subcommand's --help becomes a section.
#   cmake -DUKDYN=path/to/ukdyn -DHELP2MAN=/usr/bin/help2man -DOUT=ukdyn.1.gz -P man_page.cmake
get_filename_component(dir ${OUT} DIRECTORY)
set(include_file ${dir}/ukdyn.h2m)
set(text "[DESCRIPTION]\nukdyn computes the motion of constrained mechanical systems from the\n")
string(APPEND text "Udwadia\\-Kalaba fundamental equation, for model files (YAML) and built\\-in examples.\n")
foreach(sub run sweep check linearize examples)
  execute_process(COMMAND ${UKDYN} ${sub} --help OUTPUT_VARIABLE help RESULT_VARIABLE code)
  if(NOT code EQUAL 0)
    message(FATAL_ERROR "${UKDYN} ${sub} --help failed (${code})")
  endif()
  string(REPLACE "\\" "\\\\" help "${help}")
  string(REPLACE "-" "\\-" help "${help}")
  string(APPEND text "\n[COMMAND ${sub}]\n.nf\n${help}.fi\n")
endforeach()
string(APPEND text "\n[SEE ALSO]\nThe documentation in /usr/share/doc/ukdyn (README.md and docs/).\n")
file(WRITE ${include_file} "${text}")
execute_process(COMMAND ${HELP2MAN} --no-info --section=1
                        "--name=equations of motion of constrained mechanical systems"
                        --include=${include_file} --output=${dir}/ukdyn.1 ${UKDYN}
                RESULT_VARIABLE code)
if(NOT code EQUAL 0)
  message(FATAL_ERROR "help2man failed (${code})")
endif()
execute_process(COMMAND gzip -9nf ${dir}/ukdyn.1 RESULT_VARIABLE code)
if(NOT code EQUAL 0)
  message(FATAL_ERROR "gzip failed (${code})")
endif()
