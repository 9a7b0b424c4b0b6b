#!/usr/bin/env bash
# The README's calibration example, reproducible: a simulated feed sweep with one 0.4 mm 2-flute
# tool (slot, a_p 50 um, the linear-edge law with K_tc 1100, K_nc 450 N/mm², K_te 8, K_ne 12 N/mm,
# runout 1.2 um at 0.5 rad, the spindle 1 % slow, helix lag, dynamometer modes 4.5/4.6/6 kHz,
# noise 0.015 N and 0.01 N steps, a truth of 0.125° and 20 discs; 0.4 s per cut at 50 kHz, as
# tests/identify/calibration_test.cpp's 2-flute sweep), and `millwatch calibrate` on it with a
# configuration that knows the cut as commanded (0.5° and 5 discs, no runout, K_tc 30 % low and
# K_ne 40 % high: what the fit must correct).
#
#   scripts/calibration_sweep.sh [FOLDER] [calibrate's options, e.g. --tared or --json]
#
# FOLDER (default: the project's build/calibration_sweep) gets the cuts (cut3.csv … cut8.csv
# with their sidecars), C.json and material.json. $MILLWATCH names the program to run (default:
# the project's Release build, built first if it is not there).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
if [ -n "${MILLWATCH:-}" ]; then
  millwatch=$(realpath -e -- "$MILLWATCH" 2>/dev/null) && [ -x "$millwatch" ] || {
    echo "calibration_sweep.sh: MILLWATCH=$MILLWATCH is no program" >&2
    exit 2
  }
else
  millwatch=$root/build/release/replay/millwatch
  if [ ! -x "$millwatch" ]; then
    cmake -S "$root" -B "$root/build/release" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
    cmake --build "$root/build/release" --target millwatch >&2
  fi
fi
if [ $# -gt 0 ] && [[ $1 != -* ]]; then
  out=$1
  shift
else
  cd "$root"
  out=build/calibration_sweep
fi
mkdir -p "$out"
cuts=()
seed=11
for feed in 3 4 5 6 8; do
  /usr/bin/python3 - "$out/cut$feed.scenario.json" "$feed" "$seed" <<'PY'
import json, sys
path, feed, seed = sys.argv[1], float(sys.argv[2]), int(sys.argv[3])
effects = {name: {"enabled": False} for name in (
    "trochoidal", "multi_pass", "min_chip", "accumulation", "deflection", "flank_wear")}
effects["runout"] = {"enabled": True, "offset_um": 1.2, "angle_rad": 0.5}
effects["helix_lag"] = {"enabled": True, "discs": 20}
effects["dynamometer"] = {"enabled": True, "natural_hz": [4500.0, 4600.0, 6000.0]}
scenario = {
    "name": f"calibration sweep: 2-flute slot at {feed:g} um/tooth",
    "model": {
        "tool": {"diameter_mm": 0.4, "flutes": 2},
        "process": {"operation": "slot", "spindle_rpm": 25000.0, "feed_per_tooth_um": feed,
                    "axial_depth_mm": 0.05, "radial_depth_mm": 0.4},
        "material": {"law": "linear_edge", "linear_edge": {
            "k_tc_N_per_mm2": 1100.0, "k_nc_N_per_mm2": 450.0, "k_te_N_per_mm": 8.0,
            "k_ne_N_per_mm": 12.0, "ploughing": "edge"}},
        "resolution": {"steps_per_rev": 2880},
        "effects": effects},
    "spindle": {"actual_rpm": 24750.0},
    "recording": {"sample_rate_hz": 50000.0, "duration_s": 0.4, "seed": seed},
    "noise": {"enabled": True, "sigma_N": [0.015, 0.015, 0.015]},
    "quantisation": {"enabled": True, "bits": 16, "range_N": [327.68, 327.68, 327.68]},
}
json.dump(scenario, open(path, "w"), indent=1)
PY
  "$millwatch" simulate "$out/cut$feed.scenario.json" -o "$out/cut$feed.csv" >/dev/null
  cuts+=("$out/cut$feed.csv")
  seed=$((seed + 1))
done
# The cut as commanded: what the monitor knows before calibrating.
cat >"$out/C.json" <<'JSON'
{
  "model": {
    "resolution": {"steps_per_rev": 720},
    "effects": {"helix_lag": {"discs": 5}, "runout": {"offset_um": 0.0}},
    "material": {"linear_edge": {"k_tc_N_per_mm2": 770.0, "k_ne_N_per_mm": 16.8}}
  }
}
JSON
"$millwatch" calibrate "${cuts[@]}" --config "$out/C.json" -o "$out/material.json" \
  --no-progress "$@"
