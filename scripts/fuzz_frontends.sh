#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Fuzzes the two front ends for a bounded time each: scripts/fuzz_frontends.sh [SECONDS]
# (default 60 per front end).
#   fuzz/fuzz_cli.py     the `ukdyn` command line (argument parsing and the runs it starts)
#   fuzz/fuzz_python.py  the Python module's entry points (parse, load, simulate, solve, control,
#                        from_callables, results)
# Both use hypothesis (python3-hypothesis) with Debian's /usr/bin/python3 and the Release build in
# build/ (scripts/test.sh builds it). Fails on the first finding: a crash, a hang (FUZZ_TIMEOUT
# seconds per input, default 60), an undocumented exit code or exception, an unclear message,
# or a result that is silently wrong (fuzz/README.md lists the promises). FUZZ_SEED=N replays
# one sequence of inputs (CI sets it); without it each run draws new ones.
set -euo pipefail
cd "$(dirname "$0")/.."

seconds=${1:-60}
if ! [[ $seconds =~ ^[0-9]+$ && $seconds -gt 0 ]]; then
  echo "usage: scripts/fuzz_frontends.sh [SECONDS]  (a positive whole number, default 60)" >&2
  exit 2
fi
if [ ! -x build/app/ukdyn ] || [ ! -d build/python/ukdyn ]; then
  echo "fuzz_frontends: build/ has no ukdyn or Python module: run scripts/test.sh first" >&2
  exit 2
fi

# the two fuzzers are one process each: they run side by side, each into its own log, printed in
# turn when both have ended; the script fails if either does
cli_log=$(mktemp) && py_log=$(mktemp)
trap 'rm -f "$cli_log" "$py_log"' EXIT
/usr/bin/python3 fuzz/fuzz_cli.py build/app/ukdyn "$seconds" >"$cli_log" 2>&1 &
cli=$!
PYTHONPATH="$PWD/build/python" /usr/bin/python3 fuzz/fuzz_python.py "$seconds" >"$py_log" 2>&1 &
py=$!
cli_status=0 && wait "$cli" || cli_status=$?
py_status=0 && wait "$py" || py_status=$?
echo "=== fuzz: the command line, ${seconds} s (exit $cli_status) ==="
cat "$cli_log"
echo "=== fuzz: the Python module, ${seconds} s (exit $py_status) ==="
cat "$py_log"
[ "$cli_status" -eq 0 ] && [ "$py_status" -eq 0 ]
