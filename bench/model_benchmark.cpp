// Cost of the physics: one revolution of the full model, an update after a parameter change
// (what identification pays per trial), and the recorded-cut simulator's throughput.
//
//   build/bench/model_benchmark --benchmark_min_time=1

#include <benchmark/benchmark.h>

#include <vector>

#include "core/model/milling_model.hpp"
#include "core/sim/cut_simulator.hpp"

namespace {

using millwatch::model::ModelConfig;

/// 2 flutes, 10 discs, 0.5° steps, every effect on.
ModelConfig full_model() {
  ModelConfig c;  // [000]'s cp-Ti case: runout, trochoid, multi-pass, min chip, accumulation,
                  // deflection and 10 helix discs are on by default
  c.resolution.steps_per_rev = 720;
  c.effects.helix_lag.discs = 10;
  c.effects.flank_wear.enabled = true;
  c.effects.flank_wear.wear_um = {5.0, 3.0};
  c.effects.dynamometer.enabled = true;
  return c;
}

void BM_FullModelRevolution(benchmark::State& state) {
  millwatch::model::MillingModel model(full_model());
  model.warm_up();
  for (auto _ : state) {
    model.step_revolution();
    benchmark::DoNotOptimize(model.forces().fx_N.data());
  }
  state.counters["steps"] = model.steps_per_rev();
  state.counters["discs"] = model.discs();
}
BENCHMARK(BM_FullModelRevolution)->Unit(benchmark::kMicrosecond);

void BM_ModelUpdateAfterRunoutChange(benchmark::State& state) {
  ModelConfig c = full_model();
  millwatch::model::MillingModel model(c);
  int i = 0;
  for (auto _ : state) {
    c.effects.runout.offset_um = 1.5 + 0.001 * (i++ % 100);
    model.update(c);
  }
}
BENCHMARK(BM_ModelUpdateAfterRunoutChange)->Unit(benchmark::kMicrosecond);

void BM_SimulatorThroughput(benchmark::State& state) {
  millwatch::sim::Scenario s;
  s.model = full_model();
  s.sample_rate_hz = static_cast<double>(state.range(0));
  s.duration_s = 0.25;
  s.spindle.actual_rpm = 25252.0;
  s.noise.enabled = true;
  s.quantisation.enabled = true;
  s.hum.enabled = true;
  s.drift.enabled = true;
  s.wear.enabled = true;
  std::vector<double> t(4096), fx(4096), fy(4096), fz(4096);
  std::int64_t samples = 0;
  for (auto _ : state) {
    state.PauseTiming();
    millwatch::sim::CutSimulator sim(s);
    state.ResumeTiming();
    while (const std::size_t n = sim.next_block(t, fx, fy, fz)) {
      samples += static_cast<std::int64_t>(n);
    }
  }
  state.SetItemsProcessed(samples);
  state.counters["x_realtime"] = benchmark::Counter(static_cast<double>(samples) / s.sample_rate_hz,
                                                    benchmark::Counter::kIsRate);
}
BENCHMARK(BM_SimulatorThroughput)->Arg(50000)->Arg(333300)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
