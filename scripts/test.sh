#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# The whole test suite: installs what is missing, builds (Release, build/) and runs every test
# through CTest.
set -euo pipefail
cd "$(dirname "$0")/.."

scripts/install-deps.sh
# (UKDYN_BUILD_BENCHMARKS=OFF in the environment leaves out the benchmark programs, which no test
# runs: CI does)
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DUKDYN_BUILD_PYTHON=ON \
  "-DUKDYN_BUILD_BENCHMARKS=${UKDYN_BUILD_BENCHMARKS:-ON}"
cmake --build build --parallel 2
# one test more than cores: a test waiting on its subprocesses (Python, Chromium, pip) leaves its
# core to the next (measured: 193 s with 2 at a time, 160 s with 3; bench/RESULTS.md, "Build time")
ctest --test-dir build --output-on-failure --parallel "$(($(nproc) + 1))"
