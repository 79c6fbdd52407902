#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# The whole test suite: installs what is missing, builds (Release, build/) and runs every test
# through CTest.
set -euo pipefail
cd "$(dirname "$0")/.."

scripts/install-deps.sh
# (UKDYN_BUILD_BENCHMARKS=OFF in the environment leaves out the benchmark programs, which no test
# runs: CI does)
# (UKDYN_TEST_SHARDS=N in the environment runs each test program's cases in one process,
# ukdyn_tests' in N, instead of one process per case: CI does; cmake/test_cases.cmake)
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DUKDYN_BUILD_PYTHON=ON \
  "-DUKDYN_BUILD_BENCHMARKS=${UKDYN_BUILD_BENCHMARKS:-ON}" "-DUKDYN_TEST_SHARDS=${UKDYN_TEST_SHARDS:-0}"
cmake --build build --parallel 2
# one test more than cores: a test waiting on its subprocesses (Python, Chromium, pip) leaves its
# core to the next (measured: 193 s with 2 at a time, 160 s with 3; bench/RESULTS.md, "Build time")
ctest --test-dir build --output-on-failure --parallel "$(($(nproc) + 1))"
