#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Fuzzes the model reader for a bounded time: scripts/fuzz.sh [SECONDS] (default 120).
# Builds fuzz/fuzz_model with clang (libFuzzer, AddressSanitizer, UndefinedBehaviorSanitizer) in
# build-fuzz/, seeds a scratch corpus with examples/models/*.yaml and fuzz/corpus/*.yaml (the
# repository is never written to), and runs the fuzzer with the dictionary fuzz/model.dict.
# Fails on any crash, uncaught exception, hang or slow input (-timeout, per input), memory
# blow-up (-rss_limit_mb), leak or sanitizer report; the offending input is kept in
# build-fuzz/artifacts/. Environment: FUZZ_TIMEOUT (seconds per input, default 10), FUZZ_RSS_MB
# (memory limit, default 2048: AddressSanitizer's own memory grows by a few KB per run, so runs of
# more than about 20 minutes need more), FUZZ_JOBS (build parallelism, default 2), FUZZ_ARGS (more
# libFuzzer flags), FUZZ_BUILD_DIR (an already configured clang build with -DUKDYN_BUILD_FUZZ=ON
# to build the target in, instead of build-fuzz/: CI reuses its sanitizer build, build-asan/).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD

seconds=${1:-120}
timeout=${FUZZ_TIMEOUT:-10}
rss_mb=${FUZZ_RSS_MB:-2048}
if ! [[ $seconds =~ ^[0-9]+$ && $seconds -gt 0 ]]; then
  echo "usage: scripts/fuzz.sh [SECONDS]  (a positive whole number, default 120)" >&2
  exit 2
fi

build=${FUZZ_BUILD_DIR:-build-fuzz}
echo "=== fuzz: building fuzz/fuzz_model (clang, libFuzzer + ASan + UBSan) in $build/ ==="
if [ -z "${FUZZ_BUILD_DIR:-}" ]; then
  CC=clang CXX=clang++ cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DUKDYN_BUILD_FUZZ=ON -DUKDYN_BUILD_TESTS=OFF -DUKDYN_BUILD_BENCHMARKS=OFF \
    -DUKDYN_BUILD_EXAMPLES=OFF >/dev/null
elif ! [ -f "$build/CMakeCache.txt" ] || ! grep -q "^UKDYN_BUILD_FUZZ:BOOL=ON" "$build/CMakeCache.txt"; then
  echo "scripts/fuzz.sh: FUZZ_BUILD_DIR=$build is not a build configured with -DUKDYN_BUILD_FUZZ=ON" >&2
  exit 2
fi
cmake --build "$build" --parallel "${FUZZ_JOBS:-2}" --target fuzz_model

scratch=$(mktemp -d "${TMPDIR:-/tmp}/ukdyn-fuzz.XXXXXX")
trap 'rm -rf "$scratch"' EXIT
mkdir -p "$scratch/corpus" "$scratch/artifacts"
cp examples/models/*.yaml fuzz/corpus/*.yaml "$scratch/corpus/"

export ASAN_OPTIONS="abort_on_error=1:detect_leaks=1:strict_string_checks=1"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"
export LSAN_OPTIONS="suppressions=$root/.ci/lsan.supp:print_suppressions=0"

echo "=== fuzz: running for ${seconds} s (at most ${timeout} s per input) ==="
status=0
# shellcheck disable=SC2086  # FUZZ_ARGS is a list of flags
"$build/fuzz/fuzz_model" "$scratch/corpus" -dict=fuzz/model.dict -max_len=4096 \
  -max_total_time="$seconds" -timeout="$timeout" -rss_limit_mb="$rss_mb" \
  -artifact_prefix="$scratch/artifacts/" -print_final_stats=1 ${FUZZ_ARGS:-} \
  2>"$scratch/log" || status=$?
grep -E "^(#[0-9]+ +DONE|stat::|Done [0-9]+ runs)" "$scratch/log" || true

if ((status != 0)) || [ -n "$(ls -A "$scratch/artifacts")" ]; then
  tail -n 60 "$scratch/log" >&2
  mkdir -p "$build/artifacts"
  cp "$scratch/artifacts/"* "$build/artifacts/" 2>/dev/null || true
  cp "$scratch/log" "$build/artifacts/fuzz.log"
  echo "fuzz: FAILED (libFuzzer exit status $status); inputs and log in $build/artifacts/" >&2
  echo "      reproduce with: $build/fuzz/fuzz_model $build/artifacts/<input>" >&2
  exit 1
fi
runs=$(grep -oE "^stat::number_of_executed_units: +[0-9]+" "$scratch/log" | grep -oE "[0-9]+$" || echo "?")
echo "fuzz: no crash, hang, leak or sanitizer report in ${runs} inputs (at most ${seconds} s)"
