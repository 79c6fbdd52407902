#!/usr/bin/env bash
# Set-up in one command: installs the Debian packages, builds ukdyn in Release (build/) and runs
# the built-in showcase: a four-bar linkage, a closed loop, with friction in the crank pin,
# written to out/four_bar_friction (trajectory.csv, summary.json and plots).
set -euo pipefail
cd "$(dirname "$0")/.."

scripts/install-deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build --parallel 2
./build/app/ukdyn run --example four_bar_friction -o out/four_bar_friction
