#!/usr/bin/env bash
# Builds millwatch (Release) and runs the main job on the bundled demo cut: simulate the cp-Ti
# slot of [000] (config/demo.json) as a dynamometer recording, replay it through the monitor as
# fast as possible and print the monitor's summary (also left in build/demo/summary.json).
set -euo pipefail
cd "$(dirname "$0")/.."

build=build/release
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" --target millwatch
mkdir -p build/demo
"$build/replay/millwatch" simulate config/demo.json -o build/demo/demo_cut.csv >/dev/null
"$build/replay/millwatch" replay build/demo/demo_cut.csv --summary build/demo/summary.json
