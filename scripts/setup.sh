#!/usr/bin/env bash
# Set-up in one command: installs the Debian packages, builds ukdyn in Release (build/) and runs
# the built-in showcase: a four-bar linkage, a closed loop, with friction in the crank pin,
# written to out/four_bar_friction (trajectory.csv, summary.json and plots).
set -euo pipefail
cd "$(dirname "$0")/.."

scripts/install-deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DUKDYN_BUILD_PYTHON=ON
cmake --build build --parallel 2
# the Python module: put build/python on /usr/bin/python3's path (a .pth file in its user
# site-packages; rewritten every time, so re-running is harmless), so that `import ukdyn` works
site_dir="$(/usr/bin/python3 -m site --user-site)"
mkdir -p "$site_dir"
printf '%s\n' "$PWD/build/python" > "$site_dir/ukdyn-build.pth"
./build/app/ukdyn run --example four_bar_friction -o out/four_bar_friction
