#!/usr/bin/env bash
# Builds and runs the whole test suite: once optimised (Release), once under AddressSanitizer
# and UndefinedBehaviorSanitizer; then fuzzes every reader for a while (scripts/fuzz.sh,
# MILLWATCH_FUZZ_SECONDS per target, default 20). Needs the packages of scripts/install-deps.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc)

echo "== Release build and tests"
cmake -S . -B build/release -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build/release -j "$jobs"
ctest --test-dir build/release -j "$jobs" --output-on-failure --timeout 600

echo "== AddressSanitizer + UndefinedBehaviorSanitizer build and tests"
# -O1 (what AddressSanitizer's authors advise) and line tables only (-g1: enough for symbolized
# reports): the sanitized build compiles in about half the time of -O2 -g (Ceres' templates in
# core/identify/window_fit.cpp: 117 s → 55 s); the whole run takes 30–34 min on a 2-core
# Intel Xeon (README).
cmake -S . -B build/asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DMILLWATCH_SANITIZE=ON \
  -DMILLWATCH_BUILD_BENCHMARKS=OFF "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" \
  "-DCMAKE_C_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" >/dev/null
cmake --build build/asan -j "$jobs"
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  LSAN_OPTIONS=suppressions=$PWD/tests/lsan.supp:print_suppressions=0 ctest --test-dir build/asan -j "$jobs" --output-on-failure --timeout 1200

echo "== libFuzzer targets (clang, ASan + UBSan)"
./scripts/fuzz.sh "${MILLWATCH_FUZZ_SECONDS:-20}"

echo "== all tests passed"
