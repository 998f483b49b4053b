#!/usr/bin/env bash
# Builds iphong with AddressSanitizer and UndefinedBehaviorSanitizer (every finding fatal) and runs
# the C++ tests and the command-line tests under them. Not part of CI: the instrumented build takes
# about 15 minutes on 2 cores. Usage: bash scripts/sanitize.sh [BUILD_DIR]
#
# The iphong CLI sends the libraries' stderr to /dev/null, so the sanitizers write their reports
# to files (log_path); any report there fails the run, and so does a test that aborts.
set -euo pipefail
cd "$(dirname "$0")/.."
build=$(realpath -m "${1:-build-sanitize}")
logs="$build/sanitizer-logs"

cmake -S . -B "$build" -DIPHONG_SANITIZE=address,undefined -DIPHONG_PYTHON=OFF -DIPHONG_BENCH=OFF \
  -DIPHONG_UNITY_BUILD=OFF -DCMAKE_BUILD_TYPE=RelWithDebInfo
cmake --build "$build" -j2
rm -rf "$logs" && mkdir -p "$logs"

asan="detect_leaks=1:log_path=$logs/asan:strict_string_checks=1:detect_stack_use_after_return=1"
export LSAN_OPTIONS="suppressions=$PWD/scripts/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:log_path=$logs/ubsan"

# Tests that decode broken PNGs on purpose need whole allocation stacks (the slow unwinder), so
# the suppression of libpng's leak can see libpng; the rest run with the fast one.
corrupt="BadDataset|ImageIo|cli\\."
status=0
ASAN_OPTIONS="$asan" ctest --test-dir "$build" -j2 --output-on-failure -E "$corrupt" || status=$?
export ASAN_OPTIONS="$asan:fast_unwind_on_malloc=0"
ctest --test-dir "$build" -j2 --output-on-failure -R "$corrupt" || status=$?
IPHONG_BUILD_DIR="$build" /usr/bin/python3 -m pytest -q tests/cli || status=$?

if compgen -G "$logs/*" > /dev/null; then
  echo "sanitizer reports:" >&2
  cat "$logs"/* >&2
  status=1
fi
if [[ $status -eq 0 ]]; then
  echo "sanitize.sh: clean (address, undefined, leaks)"
fi
exit $status
