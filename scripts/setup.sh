#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Set-up in one command: installs the Debian packages, builds ukdyn in Release (build/), installs
# the Python module into the venv .venv/ and runs the built-in showcase: a four-bar linkage, a
# closed loop, with friction in the crank pin, written to out/four_bar_friction (trajectory.csv,
# summary.json and plots).
set -euo pipefail
cd "$(dirname "$0")/.."

scripts/install-deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DUKDYN_BUILD_PYTHON=ON
cmake --build build --parallel 2
# the Python module: pip-installed (pyproject.toml, setup.py) into .venv/, a venv that sees
# Debian's packages (NumPy, pandas, matplotlib, SymPy); setup.py builds it from build/, which is
# up to date, so nothing compiles twice. No network: --no-build-isolation takes Debian's
# setuptools, --no-index keeps pip off any index. Afterwards: .venv/bin/python -c "import ukdyn"
# (or `source .venv/bin/activate`). The former set-up's path file is removed if it points here.
pth="$(/usr/bin/python3 -m site --user-site)/ukdyn-build.pth"
if [ -f "$pth" ] && grep -qxF "$PWD/build/python" "$pth"; then rm -f "$pth"; fi
/usr/bin/python3 -m venv --system-site-packages .venv
.venv/bin/python -m pip install --quiet --no-build-isolation --no-index --no-cache-dir .
./build/app/ukdyn run --example four_bar_friction -o out/four_bar_friction
