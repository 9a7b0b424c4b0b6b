#!/usr/bin/env bash
# Builds the libFuzzer targets (tests/fuzz: one per reader — CSV, LCM log, raw LCM message as
# millwatchd receives it, sidecar/monitor configuration, scenario, daemon configuration, text
# recordings with a column map (DynoWare, delimited), MATLAB .mat) with
# clang under AddressSanitizer + UndefinedBehaviorSanitizer in build/fuzz, and runs each for
# SECONDS (default 60) from its seed corpus (tests/fuzz/corpus/<target>). Fails on the first
# crash, sanitizer report, leak, time-out or broken invariant; the input that did it is left in
# build/fuzz/runs/<target>/ (crash-*, leak-*, timeout-*) — make it a regression test in the
# GoogleTest suite. New inputs the fuzzers find go to build/fuzz/runs/<target>/corpus, never
# into the seeds. Needs the packages of scripts/install-deps.sh (clang, libclang-rt-14-dev).
#   scripts/fuzz.sh [SECONDS] [TARGET...]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
shift || true
targets=("$@")
if ((${#targets[@]} == 0)); then
  targets=(csv_cut_reader lcm_log_reader force_block monitor_config scenario daemon_config
    text_recording mat_cut_reader)
fi
build=build/fuzz

# Line tables only (-g1): enough for the sanitizers' reports, and a faster build.
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang \
  -DCMAKE_CXX_COMPILER=clang++ -DMILLWATCH_FUZZ=ON -DMILLWATCH_BUILD_TESTS=OFF \
  -DMILLWATCH_BUILD_BENCHMARKS=OFF "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG" \
  "-DCMAKE_C_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG" >/dev/null
cmake --build "$build" -j "$(nproc)" --target fuzzers

export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
# Leaks in third-party code we cannot fix, each with its reason (HDF5 on a damaged v7.3 file).
export LSAN_OPTIONS=suppressions=$PWD/tests/lsan.supp:print_suppressions=0
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
fuzz_one() {  # target: runs it, leaves its exit status in $build/runs/<target>/status
  local target=$1 dict runs
  case $target in
    csv_cut_reader) dict=tests/fuzz/dict/csv.dict ;;
    text_recording) dict=tests/fuzz/dict/text.dict ;;
    mat_cut_reader) dict=tests/fuzz/dict/mat.dict ;;
    monitor_config | scenario | daemon_config) dict=tests/fuzz/dict/json.dict ;;
    *) dict= ;;
  esac
  runs="$build/runs/$target"
  mkdir -p "$runs/corpus"
  rm -f "$runs/status"
  # -rss_limit_mb: a reader must never allocate what a damaged input asks for.
  local status=0
  "$build/tests/fuzz/fuzz_$target" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=1024 \
    -max_len=16384 -print_final_stats=1 -artifact_prefix="$runs/" ${dict:+-dict="$dict"} \
    "$runs/corpus" "tests/fuzz/corpus/$target" 2>"$runs/log.txt" || status=$?
  echo "$status" >"$runs/status"
}

# One fuzzer per core at a time (each is single-threaded): the same time per target, in a
# fraction of the wall-clock time.
parallel=$(nproc)
echo "== ${#targets[@]} fuzz targets, ${seconds} s each, $parallel at a time"
for target in "${targets[@]}"; do
  while (($(jobs -rp | wc -l) >= parallel)); do
    wait -n || true
  done
  fuzz_one "$target" &
done
wait
for target in "${targets[@]}"; do
  runs="$build/runs/$target"
  echo "== fuzz_$target: ${seconds} s"
  if [ "$(cat "$runs/status" 2>/dev/null)" != 0 ]; then
    tail -n 60 "$runs/log.txt" >&2
    echo "fuzz_$target failed: the input is in $runs/ (crash-*, leak-*, timeout-*, oom-*)" >&2
    exit 1
  fi
  grep -E '^stat::(number_of_executed_units|new_units_added|peak_rss_mb)' "$runs/log.txt" |
    tr '\n' ' '
  echo
done
echo "== fuzzing passed: ${#targets[@]} targets, ${seconds} s each, no crash"
