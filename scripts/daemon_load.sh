#!/usr/bin/env bash
# millwatchd's CPU load at 333.3 kHz with identification running, fed over LCM at real time
# (issue 10: under 5 % of a core). In a private network namespace (unshare -n: needs root; no
# packet leaves the machine): bench/daemon_feeder publishes BM_DaemonLoadRealTime's simulated
# cut in 333-sample blocks (1,000 a second; --block N: N samples, at most force_block_t's 2,000)
# on udpm://239.255.76.67:7667, millwatchd monitors it with the default
# identification.cpu_budget and publishes its results on its output URL (default: the same
# group, port 7668). After a warm-up (lock, model build), the process's
# utime+stime (/proc/PID/stat) and each thread's CPU time (/proc/PID/task/*/schedstat, ns) are
# read at the start and the end of the measured span; the summary tells that every sample was
# processed.
#
#   scripts/daemon_load.sh [--seconds 30] [--warmup 8] [--block 333] [--build build/release]
#                          [--same-url] [--wake-period S] [--cpu N] [--receive batched|lcm]
#
# --wake-period S sets source.wake_period_s (default: millwatchd's, 5 ms): the sample thread
# takes the blocks in rounds S apart, each block waiting up to S for its round.
# --cpu N runs millwatchd pinned to CPU N (taskset -c N; a service: CPUAffinity=N), all its
# threads on one core: on a VM, a wake-up across cores costs an inter-processor interrupt and the
# threads' caches are not shared, so the unpinned figure moves with where the scheduler puts them.
# --receive sets source.receive (default: millwatchd's, batched): "lcm" takes the blocks from
# LCM's receive thread, woken for each datagram, instead of the sample thread's rounds.
# --same-url publishes the results on the input URL (what millwatchd did before lcm.output_url):
# its LCM receive thread then also reads the daemon's own outputs. Prints a human summary on
# stderr and one JSON line on stdout. Builds nothing: build millwatchd and daemon_feeder first.
set -euo pipefail
cd "$(dirname "$0")/.."

seconds=30
warmup=8
block=333
build=build/release
same_url=0
wake_period=
cpu=
receive=
while [ $# -gt 0 ]; do
  case "$1" in
    --seconds) seconds=$2; shift 2 ;;
    --warmup) warmup=$2; shift 2 ;;
    --block)
      block=$2
      shift 2
      if ! [[ $block =~ ^[0-9]+$ ]] || ((block < 16 || block > 2000)); then
        echo "daemon_load.sh: --block takes 16 to 2000 samples (force_block_t), not $block" >&2
        exit 2
      fi
      ;;
    --build) build=$2; shift 2 ;;
    --same-url) same_url=1; shift ;;
    --wake-period) wake_period=$2; shift 2 ;;
    --receive) receive=$2; shift 2 ;;
    --cpu)
      cpu=$2
      shift 2
      command -v taskset >/dev/null || { echo "daemon_load.sh: --cpu needs taskset (util-linux)" >&2; exit 2; }
      if ! [[ $cpu =~ ^[0-9]+$ ]] || ! taskset -c "$cpu" true 2>/dev/null; then
        echo "daemon_load.sh: --cpu takes a CPU this process may run on ($(taskset -cp $$ | sed 's/.*: //')), not $cpu" >&2
        exit 2
      fi
      ;;
    *) echo "daemon_load.sh: unknown argument $1" >&2; exit 2 ;;
  esac
done
daemon=$build/daemon/millwatchd
feeder=$build/bench/daemon_feeder
for p in "$daemon" "$feeder"; do
  [ -x "$p" ] || { echo "daemon_load.sh: $p is not built" >&2; exit 2; }
done

if [ "${MW_DAEMON_LOAD_IN_NS:-}" != 1 ]; then
  args=(--seconds "$seconds" --warmup "$warmup" --block "$block" --build "$build")
  [ "$same_url" = 1 ] && args+=(--same-url)
  [ -n "$wake_period" ] && args+=(--wake-period "$wake_period")
  [ -n "$cpu" ] && args+=(--cpu "$cpu")
  [ -n "$receive" ] && args+=(--receive "$receive")
  exec unshare -n env MW_DAEMON_LOAD_IN_NS=1 "$0" "${args[@]}"
fi

ip link set lo up
ip route add 239.0.0.0/8 dev lo
in_url="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304"
out_url="udpm://239.255.76.67:7668?ttl=0"
[ "$same_url" = 1 ] && out_url=$in_url
work=$(mktemp -d)
# (set -e holds in the trap: kill without jobs left fails, and must not become the exit status)
trap 'kill -KILL $(jobs -p) 2>/dev/null || true; rm -rf "$work"' EXIT
cache=$build/bench/daemon_load_cut.bin  # the simulated cut, kept between runs
mkdir -p "$(dirname "$cache")"

# BM_DaemonLoadRealTime's configuration: the default monitor at 333.3 kHz, 25,250 rpm.
source_fields=()
[ -n "$wake_period" ] && source_fields+=("\"wake_period_s\": $wake_period")
[ -n "$receive" ] && source_fields+=("\"receive\": \"$receive\"")
source_section=
if [ ${#source_fields[@]} -gt 0 ]; then
  source_section="\"source\": {$(IFS=,; echo "${source_fields[*]}")},"
fi
cat >"$work/d.json" <<EOF
{"monitor": {"sample_rate_hz": 333300.0, "model": {"process": {"spindle_rpm": 25250.0}}},
 $source_section
 "status_period_s": 1.0, "log_level": "warn"}
EOF
# millwatchd's own check, before anything runs: a bad --wake-period is named, not a failed run.
if ! "$daemon" --check -c "$work/d.json" >"$work/check.log" 2>&1; then
  echo "daemon_load.sh: millwatchd refuses the configuration:" >&2
  cat "$work/check.log" >&2
  exit 2
fi
# Simulate (or read) the cut before anything is measured.
"$feeder" --url "memq://" --seconds 0.001 --cache "$cache" 2>/dev/null

output_option=(--lcm-output-url "$out_url")
[ "$same_url" = 1 ] && output_option=()  # --lcm-url alone: the outputs on it too
pin=()
[ -n "$cpu" ] && pin=(taskset -c "$cpu")
"${pin[@]}" "$daemon" -c "$work/d.json" --lcm-url "$in_url" "${output_option[@]}" \
  --summary "$work/summary.json" 2>"$work/daemon.log" &
pid=$!
sleep 0.5
total=$(python3 -c "print($warmup + $seconds + 1)")
"$feeder" --url "$in_url" --seconds "$total" --block "$block" --cache "$cache" 2>"$work/feeder.log" &
feeder_pid=$!

snapshot() {  # file: "process ticks", then "tid comm ns" per thread
  {
    awk '{print "process", $14 + $15}' "/proc/$pid/stat"
    for t in /proc/"$pid"/task/*; do
      echo "$(basename "$t") $(tr ' ' '_' <"$t/comm") $(cut -d' ' -f1 "$t/schedstat")"
    done
  } >"$1"
}
sleep "$warmup"
snapshot "$work/before"
sleep "$seconds"
snapshot "$work/after"
grep '^Udp:' /proc/net/snmp | tail -1 >"$work/udp"
wait "$feeder_pid" || { cat "$work/feeder.log" >&2; exit 3; }
sleep 0.5
kill -TERM "$pid"
wait "$pid" || { cat "$work/daemon.log" >&2; exit 3; }

python3 - "$work" "$seconds" "$same_url" "$(getconf CLK_TCK)" "$block" "$wake_period" "$cpu" \
  "$receive" <<'EOF'
import json, sys
work, seconds, same_url, hz = sys.argv[1], float(sys.argv[2]), sys.argv[3] == "1", int(sys.argv[4])
block = int(sys.argv[5])
wake_period_s = float(sys.argv[6]) if sys.argv[6] else None  # None: millwatchd's default
cpu = int(sys.argv[7]) if sys.argv[7] else None  # None: not pinned
receive = sys.argv[8] or "batched"  # millwatchd's default
def read(name):
    process, threads = 0, {}
    for line in open(f"{work}/{name}"):
        w = line.split()
        if w[0] == "process":
            process = int(w[1])
        else:
            threads[int(w[0])] = (w[1], int(w[2]))
    return process, threads
p0, t0 = read("before")
p1, t1 = read("after")
summary = json.load(open(f"{work}/summary.json"))
udp = open(f"{work}/udp").read().split()
threads = {}
for tid, (comm, ns) in sorted(t1.items()):
    share = (ns - t0.get(tid, (comm, 0))[1]) / 1e9 / seconds
    threads[f"{comm}:{tid}"] = round(100 * share, 2)
fit = summary.get("fit", {})
result = {
    "bench": "daemon_load", "sample_rate_hz": 333300.0, "seconds": seconds,
    "block_samples": block, "wake_period_s": wake_period_s, "cpu": cpu, "receive": receive,
    "outputs_on_input_url": same_url,
    "process_percent_of_a_core": round(100 * (p1 - p0) / hz / seconds, 2),
    "threads_percent_of_a_core": threads,
    "samples": summary.get("samples"), "dropped_samples": summary.get("dropped_samples"),
    "windows_fitted": fit.get("windows_fitted"), "windows_skipped_for_budget":
        fit.get("windows_skipped_for_budget"),
    "udp_rcvbuf_errors": int(udp[5]) if len(udp) > 5 else None,
}
wake = f", wake period {wake_period_s * 1e3:g} ms" if wake_period_s is not None else ""
wake += f", pinned to CPU {cpu}" if cpu is not None else ""
wake += f", source.receive {receive}"
print(f"millwatchd at 333.3 kHz in {block}-sample blocks, {seconds:g} s measured{wake}"
      f" ({'outputs on the input URL' if same_url else 'outputs on their own URL'}):"
      f" process {result['process_percent_of_a_core']:.2f} % of a core", file=sys.stderr)
for name, pct in threads.items():
    print(f"  {name:24s} {pct:6.2f} %", file=sys.stderr)
print(f"  samples {result['samples']}, dropped {result['dropped_samples']}, windows fitted"
      f" {result['windows_fitted']}, skipped for the budget {result['windows_skipped_for_budget']},"
      f" UDP RcvbufErrors {result['udp_rcvbuf_errors']}", file=sys.stderr)
print(json.dumps(result))
EOF
