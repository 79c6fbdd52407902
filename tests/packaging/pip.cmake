# SPDX-License-Identifier: BSD-3-Clause
# CTest package.pip (tests/CMakeLists.txt): what scripts/setup.sh does for Python — a venv that
# sees Debian's packages, `pip install --no-build-isolation --no-index .` into it (pyproject.toml;
# setup.py builds the extension in the project's build directory, which is up to date) — then
# `import ukdyn` in the venv's python, from the venv.
#
#   cmake -DSOURCE_DIR=... -DBUILD_DIR=... -DWORK_DIR=... -P pip.cmake
cmake_minimum_required(VERSION 3.25)  # the policies of today (CMP0054: quoted arguments)
include(${CMAKE_CURRENT_LIST_DIR}/common.cmake)
require(pip.cmake SOURCE_DIR BUILD_DIR WORK_DIR)

file(REMOVE_RECURSE ${WORK_DIR})
set(venv ${WORK_DIR}/venv)
run(venv /usr/bin/python3 -m venv --system-site-packages ${venv})
run(pip ${CMAKE_COMMAND} -E env UKDYN_CMAKE_BUILD_DIR=${BUILD_DIR}
    ${venv}/bin/python -m pip install --no-build-isolation --no-index --no-cache-dir ${SOURCE_DIR})
# no user site: a former set-up's .pth there would point into a build tree
run(import ${CMAKE_COMMAND} -E env PYTHONNOUSERSITE=1 PYTHONDONTWRITEBYTECODE=1
    ${venv}/bin/python -c "import ukdyn, math
assert ukdyn.__file__.startswith('${venv}/'), ukdyn.__file__
r = ukdyn.load('pendulum').simulate(t_end=0.5)
print('import ukdyn from', ukdyn.__file__, 'pendulum to t =', r.t[-1])
assert math.isclose(r.t[-1], 0.5, rel_tol=1e-12), r.t[-1]")
message("package.pip: ok")
