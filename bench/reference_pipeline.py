#!/usr/bin/python3
"""NumPy/SciPy reference of millwatch's filter + FFT + valley steps, for the README's speed table.

On the recordings bench/pipeline_benchmark.cpp times (the simulator's default scenario, [000]'s
cp-Ti slot: 3 channels, 2 flutes, 25,252 rpm, noise and quantisation on; or --scenario FILE) at
50 kHz and 333.3 kHz, written by `millwatch simulate`, it does what the monitor's first stages do,
vectorised the way a NumPy user would (whole record at once, not streamed):
  axis map; 4th-order Butterworth low-pass at 3.3 kHz, causal (butter 'sos' + sosfilt), x, y, z;
  spindle frequency per tracker window (|Fxy| decimated to ~2.5x the cut-off, 0.25 s Hann windows
  every 0.05 s, zero-padded rfft, harmonic-sum search over commanded +-15 %, log-parabola peak
  interpolation of each harmonic, weighted mean; as core/signal/spindle_tracker);
  valleys of Fx^2 + Fy^2 one per tooth (find_peaks) refined by a three-point parabola; tooth
  periods, alpha = 360 deg T2/T per revolution.
Only the processing is timed (not reading the CSV), in CPU time like Google Benchmark's rate
counters; the figure is signal duration / processing time, best of --repeats. Human text goes to
stderr, one JSON line per recording to stdout.

Whole process (--whole-s, default 10 s, when no CSV is given): on one simulated recording at
50 kHz, the wall-clock time of this script run on it (interpreter, imports, np.loadtxt and the
processing once) against `millwatch replay --no-identify` of the same file (start, CSV parse, the
whole pipeline with the lockstep model, summary). --no-identify: replay otherwise identifies
runout and coefficients on every 30-revolution window and waits for the fits, work the reference
does not do at all. The same cut is also written as an lcm-logger log of 1 ms raw blocks
(`millwatch publish --url file://...?mode=w`) and `millwatch replay --no-identify` of that log
(with a configuration from the CSV's sidecar) timed beside them: the issue asks the LCM log
reader, like the CSV parser, not to cost more than the pipeline. Best of --whole-repeats (10),
the three alternating run by run; one JSON line {"bench": "whole_process", ...}. --whole-only:
that comparison alone.

  /usr/bin/python3 bench/reference_pipeline.py [--millwatch build/release/replay/millwatch]
  /usr/bin/python3 bench/reference_pipeline.py CUT.csv ...   # recordings with their sidecars
"""

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one core, like the C++ benchmark

import argparse  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import scipy  # noqa: E402
from numpy.lib.stride_tricks import sliding_window_view  # noqa: E402
from scipy import fft, signal  # noqa: E402

CUTOFF_HZ, ORDER = 3300.0, 4  # monitor defaults (core/monitor/monitor_config.hpp)
# The tracker's window at its upper bound and a hop of a fifth of it (millwatch's automatic
# window is 10 revolutions, 0.02–0.25 s: 24 ms at 25,252 rpm, hop half of it); its search range
# and SNR threshold are SpindleTrackerConfig's defaults.
WINDOW_S, HOP_S, SEARCH, MIN_SNR_DB = 0.25, 0.05, 0.15, 12.0
# bench/pipeline_benchmark.cpp's make_recording(): sim::Scenario's defaults and these.
BENCH_SCENARIO = {"spindle": {"actual_rpm": 25252.0}, "noise": {"enabled": True},
                  "quantisation": {"enabled": True}, "recording": {}}


def load(csv):
    """Forces (3, n) as read, sample rate, commanded rpm, flutes, axis signs, truth rpm."""
    side = json.loads(csv.with_suffix(".json").read_text())
    data = np.loadtxt(csv, delimiter=",", skiprows=1, dtype=np.float64)
    columns = {"fx": 1, "fy": 2, "fz": 3}
    axis_map = side["force_sign_convention"]["axis_map"]
    order = [columns[axis_map[a].lstrip("+-")] for a in "xyz"]
    signs = np.array([-1.0 if axis_map[a].startswith("-") else 1.0 for a in "xyz"])
    forces = np.ascontiguousarray(data[:, order].T)
    truth = side.get("truth", {}).get("spindle_rpm_actual")
    return (forces, side["sample_rate_hz"], side["process"]["spindle_rpm"],
            side["tool"]["flutes"], signs, truth)


def spindle_hz(magnitude, fs, rpm_cmd, flutes):
    """Speed per tracker window: (Hz per window, cutting per window)."""
    win = round(WINDOW_S * fs)
    hop = max(1, round(HOP_S * fs))
    nfft = 1 << (win + win // 2 - 1).bit_length()
    first = -(-win // hop) * hop - win  # windows end on multiples of the hop, as in the tracker
    frames = sliding_window_view(magnitude, win)[first::hop]
    frames = (frames - frames.mean(axis=1, keepdims=True)) * signal.get_window("hann", win)
    spec = np.abs(fft.rfft(frames, n=nfft, axis=1))
    bin_hz = fs / nfft
    f_cmd = rpm_cmd / 60.0
    harmonics = max(1, min(4 * flutes, int(0.45 * fs / (f_cmd * (1 + SEARCH)))))
    h = np.arange(1, harmonics + 1)
    # Harmonic sum on a quarter-bin grid (linear interpolation between bins).
    grid = np.arange(f_cmd * (1 - SEARCH), f_cmd * (1 + SEARCH), 0.25 * bin_hz)
    pos = np.outer(h, grid) / bin_hz
    k = pos.astype(np.intp)
    w = pos - k
    score = (spec[:, k] * (1 - w) + spec[:, k + 1] * w).mean(axis=1)
    best = grid[score.argmax(axis=1)]
    # Noise floor: median over the band the harmonics span.
    bins = np.arange(spec.shape[1])
    lo = (0.5 * best / bin_hz).astype(np.intp)
    hi = ((harmonics + 0.5) * best / bin_hz).astype(np.intp)
    inband = (bins >= lo[:, None]) & (bins <= hi[:, None])
    rows = np.arange(len(spec))
    floor = np.sort(np.where(inband, spec, np.inf), axis=1)[rows, inband.sum(axis=1) // 2]
    # Each harmonic's peak within +-2 bins, log-parabola interpolation, weighted by (h*|X|)^2.
    center = np.rint(np.outer(best, h) / bin_hz).astype(np.intp)
    near = center[:, :, None] + np.arange(-2, 3)
    kk = center - 2 + np.take_along_axis(spec[:, None, :], near, axis=2).argmax(axis=2)
    r = rows[:, None]
    mag = spec[r, kk]
    l0, l1, l2 = np.log(spec[r, kk - 1]), np.log(mag), np.log(spec[r, kk + 1])
    denom = l0 - 2 * l1 + l2
    delta = np.where(denom < 0, 0.5 * (l0 - l2) / np.where(denom < 0, denom, -1.0), 0.0)
    f_h = (kk + delta) * bin_hz / h
    weight = (h * mag) ** 2 * (mag >= 4 * floor[:, None])
    used = weight.sum(axis=1)
    f = (weight * f_h).sum(axis=1) / np.where(used > 0, used, 1.0)
    cutting = (20 * np.log10(mag.max(axis=1) / floor) >= MIN_SNR_DB) & (used > 0)
    return f, cutting


def valleys(detect, pitch):
    """Sub-sample valley positions of detect, one per tooth pitch (samples)."""
    idx, _ = signal.find_peaks(-detect, distance=max(1, int(0.7 * pitch)))
    idx = idx[(idx > 0) & (idx < len(detect) - 1)]
    # Three-point parabola through the discrete minimum and its neighbours. (A least-squares
    # parabola over +-pitch/7 samples, as wide as millwatch's cubic fit, leans towards the flat
    # side of these asymmetric valleys: alpha 147 deg instead of 158 at 333.3 kHz.)
    y0, y1, y2 = detect[idx - 1], detect[idx], detect[idx + 1]
    curvature = y0 - 2 * y1 + y2
    shift = np.where(curvature > 0, 0.5 * (y0 - y2) / np.where(curvature > 0, curvature, 1.0), 0.0)
    return idx + shift


def process(forces, fs, rpm_cmd, flutes, signs):
    """The timed part: filter, spindle speed, valleys, tooth periods and alpha."""
    sos = signal.butter(ORDER, CUTOFF_HZ, fs=fs, output="sos")
    y = signal.sosfilt(sos, forces * signs[:, None], axis=1)
    detect = y[0] ** 2 + y[1] ** 2
    decimation = max(1, int(fs / (2.5 * CUTOFF_HZ)))
    f, cutting = spindle_hz(np.sqrt(detect[::decimation]), fs / decimation, rpm_cmd, flutes)
    f_spindle = np.median(f[cutting])
    v = valleys(detect, fs / (f_spindle * flutes))
    # Revolutions start at flute 0 (CE1): the flute whose teeth hold the larger peaks.
    peaks = np.maximum.reduceat(detect, v.astype(np.intp))[:-1]
    ce1 = int(np.argmax([peaks[j::flutes].mean() for j in range(flutes)]))
    n_rev = (len(v) - 1 - ce1) // flutes
    starts = v[ce1: ce1 + flutes * n_rev + 1]
    periods = np.diff(starts).reshape(n_rev, flutes) / fs
    period = periods.sum(axis=1)
    alpha = 360.0 * periods[:, 1] / period if flutes > 1 else np.full(n_rev, 360.0)
    return f_spindle * 60.0, period, alpha


def simulate(millwatch, scenario, rate_hz, duration_s, workdir, tag="reference"):
    s = json.loads(Path(scenario).read_text() if scenario else json.dumps(BENCH_SCENARIO))
    s["recording"]["sample_rate_hz"] = rate_hz
    workdir.mkdir(parents=True, exist_ok=True)
    scen = workdir / f"{tag}_{rate_hz:.0f}hz.scenario.json"
    scen.write_text(json.dumps(s, indent=1))
    csv = workdir / f"{tag}_{rate_hz:.0f}hz.csv"
    subprocess.run([millwatch, "simulate", str(scen), "-o", str(csv),
                    "--duration", str(duration_s)], check=True, stdout=subprocess.DEVNULL)
    return csv


def lcm_log_of(millwatch, csv):
    """The cut as an lcm-logger log of 1 ms raw blocks, and a configuration to replay it with
    (the log holds the samples alone: the rate, model and axis map come from the sidecar)."""
    log = csv.with_suffix(".lcmlog")
    log.unlink(missing_ok=True)
    subprocess.run([millwatch, "publish", str(csv), "--url", f"file://{log.resolve()}?mode=w",
                    "--speed", "0", "--block", "50"], check=True, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL)
    sidecar = json.loads(csv.with_suffix(".json").read_text())
    config = csv.with_suffix(".lcmlog.json")
    config.write_text(json.dumps({"monitor": {
        "sample_rate_hz": sidecar["sample_rate_hz"], "model": sidecar["scenario"]["model"],
        "axis_map": sidecar["force_sign_convention"]["axis_map"]}}, indent=1))
    return log, config


def revolutions_measured(command):
    out = subprocess.run(command + ["--json"], check=True, capture_output=True, text=True).stdout
    return json.loads(out)["revolutions_measured"]


def whole_process(millwatch, scenario, duration_s, workdir, repeats):
    """Wall-clock time of the whole reference script and of millwatch replay on one CSV, and of
    millwatch replay on the same cut as an LCM log."""
    csv = simulate(millwatch, scenario, 50000.0, duration_s, workdir, "whole")
    log, config = lcm_log_of(millwatch, csv)
    replay = [millwatch, "replay", "--no-identify", "--no-progress"]
    runs = {"reference": [sys.executable, __file__, str(csv), "--repeats", "1"],
            "millwatch": replay + [str(csv)],
            "millwatch_lcmlog": replay + [str(log), "--config", str(config)]}
    # Both replays measure the same revolutions, or their times would compare different work.
    measured = {name: revolutions_measured(runs[name])
                for name in ("millwatch", "millwatch_lcmlog")}
    if measured["millwatch"] != measured["millwatch_lcmlog"]:
        sys.exit(f"the CSV and the LCM log replays differ: {measured} revolutions measured")
    # The three alternate, run by run: on a shared machine whose speed drifts over minutes, each
    # sees the same phases (run one after the other, one could be timed in a slow one).
    times = {name: [] for name in runs}
    for _ in range(repeats):
        for name, command in runs.items():
            t0 = time.perf_counter()
            subprocess.run(command, check=True, stdout=subprocess.DEVNULL,
                           stderr=subprocess.DEVNULL)
            times[name].append(time.perf_counter() - t0)
    best = {name: min(t) for name, t in times.items()}
    result = {"bench": "whole_process", "csv": str(csv), "sample_rate_hz": 50000.0,
              "duration_s": duration_s, "rows": round(duration_s * 50000.0),
              "reference_s": best["reference"], "millwatch_s": best["millwatch"],
              "ratio": best["reference"] / best["millwatch"], "repeats": repeats,
              "lcmlog": str(log), "lcmlog_bytes": log.stat().st_size,
              "millwatch_lcmlog_s": best["millwatch_lcmlog"],
              "lcmlog_ratio": best["reference"] / best["millwatch_lcmlog"],
              "revolutions_measured": measured["millwatch"]}
    print(f"  whole process, {duration_s:g} s at 50 kHz ({result['rows']} rows): reference script "
          f"{best['reference']:.3f} s, millwatch replay --no-identify {best['millwatch']:.3f} s "
          f"({result['ratio']:.1f}x), of the LCM log {best['millwatch_lcmlog']:.3f} s "
          f"({result['lcmlog_ratio']:.1f}x)", file=sys.stderr)
    print(json.dumps(result), flush=True)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("csv", nargs="*", type=Path, help="recordings (CUT.csv with CUT.json beside)")
    p.add_argument("--millwatch", default="build/release/replay/millwatch")
    p.add_argument("--scenario", help="scenario JSON (default: the C++ benchmark's recording)")
    p.add_argument("--rates", type=float, nargs="+", default=[50000.0, 333300.0])
    p.add_argument("--duration", type=float, default=2.5, help="seconds simulated (as in C++)")
    p.add_argument("--workdir", type=Path, default=Path("build/bench"))
    p.add_argument("--repeats", type=int, default=10)
    p.add_argument("--whole-s", type=float, default=10.0,
                   help="seconds of the whole-process comparison (0: none; not with CSVs given)")
    p.add_argument("--whole-repeats", type=int, default=10)
    p.add_argument("--whole-only", action="store_true",
                   help="the whole-process comparison alone (no per-rate timing)")
    a = p.parse_args()
    if a.whole_only:
        if a.csv or a.whole_s <= 0:
            p.error("--whole-only simulates its own recording: no CSV, and --whole-s above 0")
        whole_process(a.millwatch, a.scenario, a.whole_s, a.workdir, a.whole_repeats)
        return
    csvs = a.csv or [simulate(a.millwatch, a.scenario, r, a.duration, a.workdir) for r in a.rates]
    versions = {"python": platform.python_version(), "numpy": np.__version__,
                "scipy": scipy.__version__}
    print(f"NumPy/SciPy reference (filter + FFT + valleys), python {versions['python']}, "
          f"numpy {versions['numpy']}, scipy {versions['scipy']}, best of {a.repeats}",
          file=sys.stderr)
    for csv in csvs:
        forces, fs, rpm_cmd, flutes, signs, truth = load(csv)
        duration = forces.shape[1] / fs
        times, wall = [], []
        for _ in range(a.repeats):
            t0, w0 = time.process_time(), time.perf_counter()
            rpm, period, alpha = process(forces, fs, rpm_cmd, flutes, signs)
            times.append(time.process_time() - t0)
            wall.append(time.perf_counter() - w0)
        best = min(times)
        result = {"bench": "numpy_reference", "csv": str(csv), "sample_rate_hz": fs,
                  "samples": forces.shape[1], "duration_s": duration, "best_s": best,
                  "median_s": float(np.median(times)), "best_wall_s": min(wall),
                  "repeats": a.repeats, "x_realtime": duration / best,
                  "spindle_rpm_fft": rpm, "spindle_rpm_valleys": 60.0 / float(np.median(period)),
                  "spindle_rpm_truth": truth, "revolutions": len(period),
                  "alpha_deg_median": float(np.median(alpha)), "alpha_deg_std": float(alpha.std()),
                  **versions}
        print(f"  {fs / 1e3:6.1f} kHz  {forces.shape[1]} samples x 3 ({duration:.2f} s): "
              f"{1e3 * best:7.1f} ms CPU = {duration / best:6.1f}x real time; "
              f"{rpm:.1f} rpm (FFT), {result['spindle_rpm_valleys']:.1f} rpm (valleys, median), "
              f"truth {truth} rpm; {len(period)} revolutions, "
              f"alpha {np.median(alpha):.2f} deg (median; std {alpha.std():.2f})", file=sys.stderr)
        print(json.dumps(result), flush=True)
    if not a.csv and a.whole_s > 0:
        whole_process(a.millwatch, a.scenario, a.whole_s, a.workdir, a.whole_repeats)


if __name__ == "__main__":
    main()
