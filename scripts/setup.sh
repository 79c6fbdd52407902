#!/usr/bin/env bash
# Set-up in one command: installs the Debian packages, builds ukdyn in Release (build/) and runs
# the built-in example.
set -euo pipefail
cd "$(dirname "$0")/.."

scripts/install-deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build --parallel 2
./build/examples/pendulum_demo
