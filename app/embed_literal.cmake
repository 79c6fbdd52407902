# SPDX-License-Identifier: BSD-3-Clause
# Shared by embed.cmake and embed_viewer.cmake (included by both, at build time): a file as a C++
# string literal, and writing a generated source only when its text changed.

set(delim "ukdyn_embed")

# ukdyn_literal(PATH OUT_VAR): the text of PATH as raw string literals with a delimiter the file
# must not contain, in pieces of at most 60000 bytes (MSVC's limit is 64 kB; GCC and clang have
# none, but a single 850 kB literal is slow to compile); adjacent literals are concatenated.
function(ukdyn_literal path out_var)
  file(READ "${path}" text)
  ukdyn_text_literal("${text}" "${path}" pieces)
  set(${out_var} "${pieces}" PARENT_SCOPE)
endfunction()

# ukdyn_text_literal(TEXT WHAT OUT_VAR): TEXT as ukdyn_literal's literals (WHAT names it in errors).
function(ukdyn_text_literal text path out_var)
  string(FIND "${text}" ")${delim}\"" clash)
  if(NOT clash EQUAL -1)
    message(FATAL_ERROR "${path} contains the raw-string delimiter ')${delim}\"'")
  endif()
  string(LENGTH "${text}" length)
  set(pieces "")
  set(start 0)
  while(start LESS length)
    string(SUBSTRING "${text}" ${start} 60000 piece)
    string(APPEND pieces "R\"${delim}(${piece})${delim}\"\n")
    math(EXPR start "${start} + 60000")
  endwhile()
  if(pieces STREQUAL "")
    set(pieces "\"\"")
  endif()
  set(${out_var} "${pieces}" PARENT_SCOPE)
endfunction()

# ukdyn_write_if_changed(PATH TEXT): an unchanged input does not trigger a recompile.
function(ukdyn_write_if_changed path text)
  set(old "")
  if(EXISTS "${path}")
    file(READ "${path}" old)
  endif()
  if(NOT "${old}" STREQUAL "${text}")
    file(WRITE "${path}" "${text}")
  endif()
endfunction()
