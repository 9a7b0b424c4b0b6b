#!/usr/bin/env bash
# Builds millwatch (Release) and, in one run, benchmarks the whole pipeline with the lockstep
# model (bench/pipeline_benchmark), the model and simulator (bench/model_benchmark) and the
# NumPy/SciPy reference of the filter + FFT + valley steps (bench/reference_pipeline.py, Debian's
# python3-scipy), and the whole process on a 10 s CSV (the reference script against
# `millwatch replay --no-identify`: the reference identifies nothing; and the replay of the same
# cut as an LCM log); prints the README's performance table (Markdown) on stdout, progress on stderr.
# Raw results stay in build/bench/. Needs the packages of scripts/install-deps.sh.
set -euo pipefail
cd "$(dirname "$0")/.."

build=build/release
out=build/bench
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" --target pipeline_benchmark model_benchmark millwatch millwatchd \
  daemon_feeder >&2
mkdir -p "$out"
# The pipeline and the NumPy reference take turns, three rounds each, and the table takes each
# one's best: on a shared machine whose speed drifts over minutes, both then see the same phases
# (timed one after the other, a ratio could compare a fast phase with a slow one).
rm -f "$out"/pipeline_round*.json "$out"/reference_round*.jsonl
recordings=()  # simulated in the first round, read again in the others
for round in 1 2 3; do
  echo "== pipeline_benchmark BM_Pipeline, round $round" >&2
  "$build/bench/pipeline_benchmark" --benchmark_filter='^BM_Pipeline/' --benchmark_repetitions=3 \
    --benchmark_out="$out/pipeline_round$round.json" --benchmark_out_format=json >&2
  echo "== NumPy/SciPy reference, round $round" >&2
  /usr/bin/python3 bench/reference_pipeline.py --millwatch "$build/replay/millwatch" \
    --workdir "$out" --whole-s 0 "${recordings[@]}" >"$out/reference_round$round.jsonl"
  recordings=("$out/reference_50000hz.csv" "$out/reference_333300hz.csv")
done
echo "== pipeline_benchmark, the rest" >&2
"$build/bench/pipeline_benchmark" --benchmark_filter='-^BM_Pipeline/' --benchmark_repetitions=3 \
  --benchmark_out="$out/pipeline.json" --benchmark_out_format=json >&2
echo "== model_benchmark" >&2
"$build/bench/model_benchmark" --benchmark_repetitions=3 --benchmark_out="$out/model.json" \
  --benchmark_out_format=json >&2
echo "== whole process: the reference script against millwatch replay" >&2
/usr/bin/python3 bench/reference_pipeline.py --millwatch "$build/replay/millwatch" \
  --workdir "$out" --whole-only >"$out/reference.jsonl"

/usr/bin/python3 - "$out" <<'EOF'
import json, sys
out = sys.argv[1]
runs = {}  # benchmark name -> its repetitions
for f in ("pipeline_round1", "pipeline_round2", "pipeline_round3", "pipeline", "model"):
    for r in json.load(open(f"{out}/{f}.json"))["benchmarks"]:
        if r["run_type"] == "iteration":
            runs.setdefault(r["run_name"], []).append(r)
ref = {}  # rate -> the best round (each the best of its repeats)
for k in (1, 2, 3):
    for r in (json.loads(l) for l in open(f"{out}/reference_round{k}.jsonl")):
        rate = round(r["sample_rate_hz"])
        if r["bench"] == "numpy_reference" and (
                rate not in ref or r["x_realtime"] > ref[rate]["x_realtime"]):
            ref[rate] = r
lines = [json.loads(l) for l in open(f"{out}/reference.jsonl")]
whole = next((r for r in lines if r["bench"] == "whole_process"), None)
best = lambda name, key: max(r[key] for r in runs[name])  # best of the repetitions
print("| sample rate | millwatch full pipeline, lockstep on | the reference's steps (lockstep off)"
      " | latency per revolution, p99 / worst / mean | NumPy/SciPy filter + FFT + valleys"
      " | simulator, full model + measurement chain |")
print("|---|---|---|---|---|---|")
for rate, label, block, target in ((50000, "50 kHz", 50, 600), (333300, "333.3 kHz", 333, 120)):
    pipe, steps = f"BM_Pipeline/{rate}/{block}/1", f"BM_Pipeline/{rate}/{block}/0"
    sim = f"BM_SimulatorThroughput/{rate}"
    worst = max(r["latency_worst_us"] for r in runs[pipe])
    p99 = max(r["latency_p99_us"] for r in runs[pipe])
    mean = sum(r["latency_mean_us"] for r in runs[pipe]) / len(runs[pipe])
    reference = ref[rate]["x_realtime"]
    print(f"| {label} | {best(pipe, 'x_realtime'):.0f}× real time (target ≥ {target}×),"
          f" {best(pipe, 'x_realtime') / reference:.1f}× the reference (target ≥ 2×)"
          f" | {best(steps, 'x_realtime'):.0f}× real time, {best(steps, 'x_realtime') / reference:.1f}×"
          " the reference (target ≥ 5×)"
          f" | {p99:.0f} µs / {worst / 1e3:.2f} ms / {mean:.1f} µs (target < 100 µs / 1 ms)"
          f" | {reference:.0f}× real time"
          f" | {best(sim, 'x_realtime'):.1f}× real time ({best(sim, 'items_per_second') / 1e6:.2f}"
          " M samples/s) |")
jitter = runs.get("BM_MachineJitter/10/iterations:1/real_time", [])
if jitter:
    print(f"\nThe machine alone (`BM_MachineJitter`: a fixed job of"
          f" {sum(r['job_mean_us'] for r in jitter) / len(jitter):.1f} µs run back to back for"
          f" {len(jitter)} × 10 s, wall clock): p99 {max(r['job_p99_us'] for r in jitter):.0f} µs,"
          f" worst {max(r['job_worst_us'] for r in jitter) / 1e3:.2f} ms — what preemption adds to"
          " any job; a worst latency above that would be the pipeline's own.")
ramp = runs.get("BM_PipelineLatencyThroughARamp/iterations:1/real_time", [])
if ramp:
    print(f"\nThrough a speed ramp at 333.3 kHz (`BM_PipelineLatencyThroughARamp`: 25,000 → 26,000"
          f" rpm, the default model rebuilt {ramp[0]['model_builds']:.0f} times on the model"
          f" builder's thread, blocks handed over at real time, {len(ramp)} runs): latency p99"
          f" {max(r['latency_p99_us'] for r in ramp):.0f} µs, worst"
          f" {max(r['latency_worst_us'] for r in ramp) / 1e3:.2f} ms (target < 100 µs / 1 ms).")
rev = min(r["real_time"] for r in runs["BM_FullModelRevolution"]) / 1e3
upd = min(r["real_time"] for r in runs["BM_ModelUpdateAfterRunoutChange"]) / 1e3
if whole:
    print(f"\nWhole process, {whole['duration_s']:g} s at 50 kHz ({whole['rows']:,} rows of CSV):"
          f" `millwatch replay --no-identify` {whole['millwatch_s'] * 1e3:.0f} ms, the reference"
          f" script (np.loadtxt + the steps above) {whole['reference_s'] * 1e3:.0f} ms:"
          f" {whole['ratio']:.1f}× (target ≥ 10×); wall clock, best of {whole['repeats']}.")
    if "millwatch_lcmlog_s" in whole:
        print(f"The same cut as an lcm-logger log ({whole['lcmlog_bytes'] / 1e6:.1f} MB, 1 ms raw"
              f" blocks): `millwatch replay --no-identify` {whole['millwatch_lcmlog_s'] * 1e3:.0f}"
              f" ms, {whole['lcmlog_ratio']:.1f}× the reference script on the CSV"
              f" ({whole['revolutions_measured']:,} revolutions measured from each).")
daemon = [r for name, rs in runs.items() if name.startswith("BM_DaemonLoadRealTime/60/0/") for r in rs]
unbudgeted = [r for name, rs in runs.items() if name.startswith("BM_DaemonLoadRealTime/5/1000/")
              for r in rs]
median = lambda rs, key: sorted(r[key] for r in rs)[len(rs) // 2]
if daemon:
    print(f"\nDaemon at 333.3 kHz with identification running, fed at real time and taken in"
          f" millwatchd's 5 ms rounds (`BM_DaemonLoadRealTime`, 60 s, median of {len(daemon)}),"
          f" identification.cpu_budget"
          f" {median(daemon, 'budget'):g}: the sample thread {100 * median(daemon, 'sample_thread_of_a_core'):.1f} %"
          f" of a core, the process (sample thread and identification worker)"
          f" {100 * median(daemon, 'process_of_a_core'):.1f} % (target < 5 %); windows fitted"
          f" {median(daemon, 'fitted_per_s'):.3f}/s, skipped for the budget"
          f" {median(daemon, 'skipped_for_budget_per_s'):.1f}/s.")
if unbudgeted:
    print(f"Without a budget (cpu_budget 1, 5 s): the sample thread"
          f" {100 * median(unbudgeted, 'sample_thread_of_a_core'):.1f} %, the process"
          f" {100 * median(unbudgeted, 'process_of_a_core'):.0f} %; windows fitted"
          f" {median(unbudgeted, 'fitted_per_s'):.1f}/s, dropped {median(unbudgeted, 'dropped_per_s'):.1f}/s.")
cpu = next((l.split(":")[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")))
r = next(iter(ref.values()))
print(f"\nFull model, one revolution (2 flutes, 10 discs, 0.5°, every effect on): {rev:.2f} ms"
      f" (target < 1 ms); model update after a runout change: {upd:.2f} ms.")
print(f"{cpu}, one core, Release; the pipeline best of {len(runs['BM_Pipeline/50000/50/1'])}"
      f" repetitions and NumPy/SciPy best of 3 × {r['repeats']}, in three rounds taking turns"
      f" (latency: the largest p99 and worst, and the mean; the rest best of 3) (Python"
      f" {r['python']}, NumPy {r['numpy']}, SciPy {r['scipy']}); × real time from CPU time,"
      f" latency from the wall clock.")
EOF
# millwatchd itself over LCM (needs root for unshare -n; skipped, saying so, without it).
if unshare -n true 2>/dev/null; then
  echo "== millwatchd over LCM (scripts/daemon_load.sh, three runs)" >&2
  for _ in 1 2 3; do  # the machine's noise shows most here: the median of three
    scripts/daemon_load.sh --build "$build" --seconds 20
  done >"$out/daemon_load.jsonl"
  # Identification fits a window about once a minute within its budget: a span of three minutes
  # measures the process with its fits, not only between them.
  echo "== millwatchd over LCM with identification's fits (scripts/daemon_load.sh, 180 s)" >&2
  scripts/daemon_load.sh --build "$build" --seconds 180 >"$out/daemon_load_fits.json"
  # As a service would run it with CPUAffinity=: its threads on one core (the last this script
  # may use; python: the affinity mask may be a list with gaps).
  pinned_cpu=$(python3 -c 'import os; print(max(os.sched_getaffinity(0)))')
  echo "== the same, millwatchd pinned to CPU $pinned_cpu (scripts/daemon_load.sh --cpu, 180 s)" >&2
  scripts/daemon_load.sh --build "$build" --seconds 180 --cpu "$pinned_cpu" \
    >"$out/daemon_load_pinned.json"
  /usr/bin/python3 - "$out/daemon_load.jsonl" "$out/daemon_load_fits.json" \
    "$out/daemon_load_pinned.json" <<'EOF'
import json, sys
runs = sorted((json.loads(l) for l in open(sys.argv[1])), key=lambda r: r["process_percent_of_a_core"])
r = runs[len(runs) // 2]
def share(run, prefix):  # the CPU share of a run's threads named prefix*
    return sum(v for k, v in run["threads_percent_of_a_core"].items() if k.startswith(prefix))
others = ", ".join(f"{x['process_percent_of_a_core']:.1f} %" for x in runs if x is not r)
# The blocks read by the sample thread in its rounds (source.receive "batched", the default), or
# by LCM's receive thread.
receive = (" (it reads the blocks itself)" if r.get("receive", "batched") == "batched" else
           f", LCM's receive thread {share(r, 'mw-lcm-receive'):.1f} %")
print(f"\nmillwatchd at 333.3 kHz over LCM (`scripts/daemon_load.sh`, {r['seconds']:g} s, median of"
      f" {len(runs)}): the process {r['process_percent_of_a_core']:.1f} % of a core between fits"
      f" (the other runs {others}): the sample thread {share(r, 'mw-sample'):.1f} %{receive},"
      f" the publisher {share(r, 'mw-publish'):.1f} %,"
      f" identification {share(r, 'mw-identify'):.1f} % ({r['windows_fitted']}"
      f" window{'s' if r['windows_fitted'] != 1 else ''} fitted,"
      f" {r['windows_skipped_for_budget']} skipped for the budget); identification's budget adds"
      f" about 0.5 % on average (cpu_budget 0.005); target < 5 % with it; {r['dropped_samples']}"
      f" samples dropped.")
for path, how in ((sys.argv[2], "unpinned"), (sys.argv[3], "pinned to one core")):
    f = json.load(open(path))
    fitted = f['windows_fitted']
    identify = share(f, 'mw-identify')
    # The summary counts the fits of the whole run (warm-up and drain too); the CPU shares are
    # those of the measured seconds alone, which may hold none (the budget's rest after a long
    # fit can outlast them).
    none_inside = " (no fit fell within the measured seconds)" if identify == 0 else ""
    print(f"With identification's fits, {how}, over {f['seconds']:g} s ({fitted}"
          f" window{'s' if fitted != 1 else ''} fitted in the whole run,"
          f" {f['windows_skipped_for_budget']} skipped for the budget): the process"
          f" {f['process_percent_of_a_core']:.2f} % of a core (target < 5 %), identification"
          f" {identify:.2f} % of it{none_inside}; {f['dropped_samples']} samples dropped.")
EOF
else
  echo "== millwatchd over LCM: skipped (unshare -n needs root)" >&2
fi
