# SPDX-License-Identifier: BSD-3-Clause
# CTest package.deb (tests/CMakeLists.txt): build the Debian package with CPack, extract it with
# dpkg -x into a temporary directory, and run what it holds from there: `ukdyn run --example
# pendulum` and `import ukdyn` in Debian's /usr/bin/python3.
#
#   cmake -DBUILD_DIR=... -DWORK_DIR=... -DVERSION=... -P deb.cmake
cmake_minimum_required(VERSION 3.25)  # the policies of today (CMP0054: quoted arguments)
include(${CMAKE_CURRENT_LIST_DIR}/common.cmake)
require(deb.cmake BUILD_DIR WORK_DIR VERSION)

file(REMOVE_RECURSE ${WORK_DIR})
get_filename_component(cmake_bin ${CMAKE_COMMAND} DIRECTORY)
find_program(CPACK cpack HINTS ${cmake_bin} REQUIRED)

# the package, under its Debian name
run(cpack ${CPACK} -G DEB --config ${BUILD_DIR}/CPackConfig.cmake -B ${WORK_DIR}/cpack)
run(arch dpkg --print-architecture)
string(STRIP "${last_output}" arch)
set(deb ${WORK_DIR}/cpack/ukdyn_${VERSION}_${arch}.deb)
if(NOT EXISTS ${deb})
  file(GLOB made ${WORK_DIR}/cpack/*.deb)
  message(FATAL_ERROR "no ${deb} (made: ${made})")
endif()
file(SIZE ${deb} size)
message("${deb}: ${size} bytes")

# its control fields: Depends names the run-time libraries (dpkg-shlibdeps) and Python
run(info dpkg-deb --field ${deb} Package Version Architecture Depends Recommends)
foreach(dep "libc6" "libstdc\\+\\+6" "libsundials-cvode" "libyaml-cpp" "libginac" "libhdf5"
            "libcholmod" "python3-numpy")
  if(NOT last_output MATCHES "Depends:[^\n]*${dep}")
    message(FATAL_ERROR "Depends lacks ${dep}")
  endif()
endforeach()
# and Recommends what the module's optional functions import (pyproject.toml's extras)
foreach(rec "python3-matplotlib" "python3-pandas" "python3-xarray")
  if(NOT last_output MATCHES "Recommends:[^\n]*${rec}")
    message(FATAL_ERROR "Recommends lacks ${rec}")
  endif()
endforeach()

# Debian's own checks (issue #33 item 2): no lintian error or warning; the two warnings CPack's
# layout makes are overridden with their reasons in the package (cmake/debian/lintian-overrides)
find_program(LINTIAN lintian)
if(LINTIAN)
  execute_process(COMMAND ${LINTIAN} --tag-display-limit 0 ${deb} OUTPUT_VARIABLE lint
                  ERROR_VARIABLE lint_err RESULT_VARIABLE lint_code)
  message("lintian (exit ${lint_code}):\n${lint}")
  if(lint MATCHES "(^|\n)[EW]: " OR NOT lint_code EQUAL 0)
    message(FATAL_ERROR "lintian reports errors or warnings:\n${lint}${lint_err}")
  endif()
else()
  message(FATAL_ERROR "lintian not found (scripts/install-deps.sh installs it)")
endif()

# extracted, not installed: everything runs from the temporary tree
set(root ${WORK_DIR}/root)
run(extract dpkg -x ${deb} ${root})
# the licence, where Debian keeps it
set(copyright ${root}/usr/share/doc/ukdyn/copyright)
if(NOT EXISTS ${copyright})
  message(FATAL_ERROR "the package has no ${copyright}")
endif()
file(READ ${copyright} text)
if(NOT text MATCHES "License: BSD-3-Clause")
  message(FATAL_ERROR "${copyright} does not state the BSD-3-Clause licence")
endif()
# the man page, the bash completion, the changelog, the docs and the examples
foreach(f usr/share/man/man1/ukdyn.1.gz usr/share/bash-completion/completions/ukdyn
          usr/share/doc/ukdyn/changelog.gz usr/share/doc/ukdyn/README.md
          usr/share/doc/ukdyn/docs/model-format.md usr/share/doc/ukdyn/examples/models/pendulum.yaml)
  if(NOT EXISTS ${root}/${f})
    message(FATAL_ERROR "the package has no /${f}")
  endif()
endforeach()
run(man_page gzip -dc ${root}/usr/share/man/man1/ukdyn.1.gz)
if(NOT last_output MATCHES "\\.SH NAME\nukdyn \\\\- equations of motion" OR NOT last_output MATCHES "COMMAND RUN")
  message(FATAL_ERROR "the man page lacks its NAME or the run subcommand's section")
endif()
set(ukdyn ${root}/usr/bin/ukdyn)
run(ldd ldd ${ukdyn})
if(last_output MATCHES "not found")
  message(FATAL_ERROR "${ukdyn}: a library is not found")
endif()
run(version ${ukdyn} --version)
if(NOT last_output MATCHES "^ukdyn ${VERSION}\n")
  message(FATAL_ERROR "ukdyn --version: '${last_output}', expected 'ukdyn ${VERSION}'")
endif()
run(command ${ukdyn} run --example pendulum -o ${WORK_DIR}/out)
foreach(f trajectory.csv summary.json)
  if(NOT EXISTS ${WORK_DIR}/out/${f})
    message(FATAL_ERROR "ukdyn run wrote no ${f}")
  endif()
endforeach()

# the Python module, from the extracted tree only (no user site: scripts/setup.sh's .pth there
# points into the build tree)
set(site ${root}/usr/lib/python3/dist-packages)
run(python ${CMAKE_COMMAND} -E env PYTHONPATH=${site} PYTHONNOUSERSITE=1 PYTHONDONTWRITEBYTECODE=1
    /usr/bin/python3 -c "import ukdyn, math
assert ukdyn.__file__.startswith('${site}/'), ukdyn.__file__
r = ukdyn.load('pendulum').simulate(t_end=0.5)
print('import ukdyn from', ukdyn.__file__, 'pendulum to t =', r.t[-1])
assert math.isclose(r.t[-1], 0.5, rel_tol=1e-12), r.t[-1]")
message("package.deb: ok")
