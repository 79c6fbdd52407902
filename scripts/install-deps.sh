#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Installs the Debian packages that ukdyn needs to build, test and benchmark. Idempotent: when
# everything is installed already it does not touch apt at all.
set -euo pipefail

packages=(
  build-essential cmake ninja-build    # compiler and build system
  lld                                  # LLVM's linker: links each program in a fifth of GNU ld's CPU (CMakeLists.txt, UKDYN_LINKER)
  file                                 # cpack -G DEB: CPack's dpkg-shlibdeps step detects ELF files with it
  libeigen3-dev                        # linear algebra and AutoDiff
  libboost-dev                         # Boost.Odeint: RK4, Dormand-Prince, Fehlberg
  libsundials-dev                      # SUNDIALS CVODE: BDF for stiff problems
  libhdf5-dev                          # HDF5 trajectories
  nlohmann-json3-dev                   # JSON run summaries
  libginac-dev                         # symbolic expressions of model files
  libsuitesparse-dev                   # CHOLMOD / SuiteSparseQR: the sparse engine
  libsiconos-numerics-dev              # Siconos Numerics: the LCP of unilateral contacts (docs/contact.md)
  libyaml-cpp-dev                      # model files
  libcli11-dev                         # the ukdyn command line
  python3-matplotlib                   # plots of ukdyn run
  pybind11-dev python3-dev             # the Python module (python/)
  python3-venv python3-setuptools python3-wheel  # pip install . into .venv/ (pyproject.toml: setuptools drives CMake)
  python3-numpy python3-pandas         # its arrays and DataFrames
  python3-sympy                        # SymPy-defined models
  python3-scipy                        # the LQR example's Riccati solver (python/examples/lqr_cart_pendulum.py)
  python3-pytest                       # its tests
  python3-hypothesis                   # the front ends' fuzzing (fuzz/fuzz_cli.py, fuzz_python.py)
  jupyter-notebook python3-nbconvert python3-ipykernel  # the notebook in examples/, run by the tests
  libgtest-dev libgmock-dev            # tests
  libbenchmark-dev                     # benchmarks
  liburdfdom-dev                       # URDF import of kinematic trees (src/multibody/tree/urdf.cpp)
  libtinyxml-dev                       # the XML parser under urdfdom 3: located XML errors (src/multibody/tree/urdf_xml.cpp)
  libmujoco-dev                        # bench_mujoco: MuJoCo 2.2.2 on the shared problems (optional)
  clang libclang-rt-14-dev             # fuzz/: libFuzzer and the sanitizer runtimes of clang
  procps util-linux                    # .ci/run: pgrep (stopping its background builds), chrt (their priority)
  clang-format                         # scripts/format.sh: the house style, checked by CI
  libjs-three                          # three.js, embedded in animation.html (ukdyn run --viewer)
  help2man lintian                     # the man page from --help; Debian's checks of the .deb (tests/packaging)
  chromium chromium-driver python3-selenium  # the viewer's tests in a headless browser
  python3-pil                          # the viewer's tests read the canvas's pixels
  python3-xarray                       # ukdyn.sweep: a grid as an xarray.Dataset
  python3-dask python3-distributed     # ukdyn.sweep(client=...): ensembles on Dask workers (tested on a LocalCluster)
  doxygen python3-sphinx               # the API reference, C++ and Python (scripts/build-docs.sh)
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]} == 0)); then
  exit 0
fi

sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
echo "install-deps: installing ${missing[*]}"
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
