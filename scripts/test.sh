#!/usr/bin/env bash
# Checks the C++ sources' format (clang-format), then builds and runs the whole test suite: what
# ships built optimised by GCC (Release: the programs and the benchmarks, warning-free), its
# install and Debian package checked and the vector kernels' tests run on it; every test built
# by clang under AddressSanitizer and UndefinedBehaviorSanitizer; then every reader fuzzed for a
# while (scripts/fuzz.sh, MILLWATCH_FUZZ_SECONDS per target, default 20). Needs the packages of
# scripts/install-deps.sh.
#
# The whole suite runs once, sanitized: running it in Release as well took 10 of the command's
# 30 minutes (build 7.8, run 2.1). The tests check behaviour, which neither the optimisation
# level nor the compiler changes (x86-64's SSE2 arithmetic rounds the same at -O1 and -O3, with
# GCC and with clang, and nothing is contracted into FMAs: -ffp-contract=off). clang builds the
# sanitized suite in 7.4 min where GCC took 12.4 (the tests' own code 3.6 min of CPU against
# 10.6); what only GCC's code generation could break — the vector kernels with their target
# attributes and intrinsics, bit for bit against their scalar twins, and the pipeline they make
# up — is tested on the GCC build that ships (MILLWATCH_TESTS below). `ctest --test-dir
# build/release` runs the whole suite on GCC's optimised build, and the benchmarks run it.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc)

echo "== clang-format (.clang-format) on every C++ source"
# The style is checked, not fixed: a file that would change fails the run, naming the line.
# The files git tracks; outside a clone (or untracked in another repository), every source
# under the folders that hold them.
mkdir -p build
git ls-files -z -- '*.cpp' '*.hpp' '*.h' >build/format_files 2>/dev/null || true
if [[ ! -s build/format_files ]]; then
  find bench core daemon msgs replay shell tests \( -name '*.cpp' -o -name '*.hpp' -o -name '*.h' \) \
    -print0 >build/format_files
fi
format_count=$(tr -cd '\0' <build/format_files | wc -c)
if ((format_count == 0)); then
  echo "clang-format: no C++ sources found to check" >&2
  exit 1
fi
xargs -0 -r clang-format --dry-run -Werror <build/format_files
echo "clang-format: $format_count files clean"

echo "== Release build of what ships, its install and Debian package, the kernels' tests"
# A build folder of its own, so that build/release keeps the whole suite for bench.sh, demo.sh
# and developers. Of the tests, only those of the code GCC's vectorisation and target attributes
# compile (the low-pass kernels, the tracker's spectra and floors, the conditioner and the input
# check, the ring's rows, the grid line, the synchronous average, the residual sums, the
# revolution's features, the lockstep model, the steady state's removal, the decimal parsers)
# and of the pipeline they make up; with them, CTest's `package` (tests/package/package_test.sh).
gcc_tests='^(butterworth_lowpass|grid_lowpass|harmonic_floors|spindle_tracker|conditioner'
gcc_tests+='|input_check|sample_ring|grid_line|sync_average|residual_sums|revolution_features'
gcc_tests+='|lockstep|steady_state|decimal_number|decimal_row|pipeline)_test$'
# (Tests on explicitly: a build/shipped of before, configured without them, would otherwise keep
# that and run nothing, not even the package's check, which --no-tests=error also catches.)
cmake -S . -B build/shipped -G Ninja -DCMAKE_BUILD_TYPE=Release -DMILLWATCH_BUILD_TESTS=ON \
  "-DMILLWATCH_TESTS=$gcc_tests" >/dev/null
cmake --build build/shipped -j "$jobs"
ctest --test-dir build/shipped -j "$jobs" --output-on-failure --timeout 1200 --no-tests=error

echo "== AddressSanitizer + UndefinedBehaviorSanitizer build and tests"
# -O1 (what AddressSanitizer's authors advise) and line tables only (-g1: enough for symbolized
# reports): the sanitized build compiles in about half the time of -O2 -g (GCC on Ceres' templates
# in core/identify/window_fit.cpp: 117 s → 55 s), and the tests' own code at -O0
# (cmake/MillwatchTargets.cmake). clang, as the fuzz targets are built (another folder: they
# carry libFuzzer's coverage instrumentation, under which the suite ran 8.8 min instead of ~7).
cmake -S . -B build/asan-clang -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DMILLWATCH_SANITIZE=ON \
  -DMILLWATCH_BUILD_BENCHMARKS=OFF "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" \
  "-DCMAKE_C_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" >/dev/null
cmake --build build/asan-clang -j "$jobs"
# The cp-Ti preset's two end-to-end diagnoses (tests/cli/diagnose_preset_test.cpp) run the
# Release program built above from the same sources: sanitized they took about six of the
# suite's twenty minutes of CPU, for an outcome the optimisation level does not change; the
# diagnosis's search and a final h_min profile run sanitized in tests/diagnose (on cuts whose
# cycles fit in 64 revolutions). So do the real PHM cut's diagnosis and calibration and the
# campaign of its three windows (3 of 18 minutes of CPU sanitized, 0.8 optimised): the windows
# replay sanitized in tests/cli/phm2010_replay_test.cpp, calibration and diagnosis on simulated
# cuts.
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  LSAN_OPTIONS=suppressions=$PWD/tests/lsan.supp:print_suppressions=0 \
  MILLWATCH_OPTIMISED_CLI=$PWD/build/shipped/replay/millwatch \
  ctest --test-dir build/asan-clang -j "$jobs" --output-on-failure --timeout 1200 --no-tests=error

echo "== libFuzzer targets (clang, ASan + UBSan)"
./scripts/fuzz.sh "${MILLWATCH_FUZZ_SECONDS:-20}"

echo "== all tests passed"
