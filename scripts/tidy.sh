#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Runs clang-tidy (.clang-tidy's curated checks) over the library's and the command's sources:
#   scripts/tidy.sh [FILES...]   (default: every .cpp of src/ and app/; needs build/ configured,
#                                 which writes build/compile_commands.json)
# Prints the findings and fails when there are any. About 15 minutes on two cores for the tree.
set -euo pipefail
cd "$(dirname "$0")/.."
[ -f build/compile_commands.json ] || { echo "scripts/tidy.sh: configure build/ first" >&2; exit 2; }
if (($#)); then files=("$@"); else mapfile -t files < <(git ls-files 'src/*.cpp' 'app/*.cpp' | grep -v '^app/tests/'); fi
log=$(mktemp)
trap 'rm -f "$log"' EXIT
printf '%s\n' "${files[@]}" | xargs -P "${TIDY_JOBS:-2}" -n 1 clang-tidy -p build --quiet >"$log" 2>/dev/null || true
if grep -E "(warning|error): " "$log"; then
  echo "tidy: $(grep -cE '(warning|error): ' "$log") findings" >&2
  exit 1
fi
echo "tidy: ${#files[@]} files clean"
