#!/usr/bin/env bash
# Fuzzes iphong's text parsers (tests/fuzz/fuzz_parsers.cc) with clang's libFuzzer under
# AddressSanitizer and UndefinedBehaviorSanitizer. Needs clang and libclang-rt-14-dev (Debian).
# Usage: bash scripts/fuzz.sh [SECONDS=300] [BUILD_DIR=build-fuzz]
# Findings are written to BUILD_DIR/fuzz-findings; the corpus grows in BUILD_DIR/fuzz-corpus.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-300}
build=${2:-build-fuzz}
command -v clang++ > /dev/null || { echo "fuzz.sh: clang++ is not installed" >&2; exit 2; }

CC=clang CXX=clang++ cmake -S . -B "$build" -DIPHONG_FUZZ=ON -DIPHONG_SANITIZE=address,undefined \
  -DIPHONG_PYTHON=OFF -DIPHONG_BENCH=OFF -DCMAKE_BUILD_TYPE=RelWithDebInfo
cmake --build "$build" -j2 --target iphong_fuzz iphong_fuzz_driver
mkdir -p "$build/fuzz-corpus" "$build/fuzz-findings"
"$build/tests/iphong_fuzz_driver" fixtures --seeds-to "$build/fuzz-corpus"
export ASAN_OPTIONS=detect_leaks=0  # third-party caches; leaks are the sanitize.sh run's job
"$build/tests/iphong_fuzz" "$build/fuzz-corpus" -max_total_time="$seconds" -max_len=65536 \
  -rss_limit_mb=2048 -artifact_prefix="$build/fuzz-findings/" -print_final_stats=1
