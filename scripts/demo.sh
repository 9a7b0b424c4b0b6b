#!/usr/bin/env bash
# Builds millwatch (Release) and runs the main job on the bundled demo cut: simulate the cp-Ti
# slot of [000] (config/demo.json) as a dynamometer recording, then print its summary.
set -euo pipefail
cd "$(dirname "$0")/.."

build=build/release
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" --target millwatch
mkdir -p build/demo
"$build/replay/millwatch" simulate config/demo.json -o build/demo/demo_cut.csv
