// Cost of one identification: a 30-revolution window's synchronous average (a 2-flute slot with
// runout, 4 flutes down-milling), fitted from scratch and from the previous window's result.
// Cost of one calibration (`millwatch calibrate`): five 1 s cuts of a feed sweep at 50 kHz
// through the monitor, their windows averaged, the joint fit and the classic regression (the
// recordings simulated beforehand, in memory: reading CSV files is not in the figure).

#include <benchmark/benchmark.h>

#include <algorithm>
#include <complex>
#include <span>
#include <vector>

#include "core/identify/calibration.hpp"
#include "core/identify/window_fit.hpp"
#include "core/model/steady_state.hpp"
#include "core/monitor/pipeline.hpp"
#include "core/sim/cut_simulator.hpp"
#include "tests/support/exact_window.hpp"

namespace {

using millwatch::identify::FitResult;
using millwatch::identify::MeasuredRevolution;
using millwatch::identify::WindowFitter;
namespace model = millwatch::model;

model::ModelConfig cut(int flutes, model::Operation op) {
  model::ModelConfig m = model::without_effects(model::ModelConfig{});
  m.material.law = model::ForceLawKind::kLinearEdge;
  m.tool.flutes = flutes;
  m.tool.diameter_mm = 0.5;
  m.process.operation = op;
  m.process.radial_depth_mm = op == model::Operation::kSlot ? 0.5 : 0.25;
  m.process.feed_per_tooth_um = 3.0;
  m.process.axial_depth_mm = 0.05;
  model::set_effect(m, "runout", true);
  m.effects.runout.offset_um = 1.2;
  m.effects.runout.angle_rad = 0.3;
  model::set_effect(m, "helix_lag", true);
  return m;
}

/// Fits `truth`'s measured window from `truth` without runout (or, from_previous, from the
/// first fit's result) each iteration; the evaluations per fit as a counter.
void fit_window(benchmark::State& state, const model::ModelConfig& truth, bool from_previous,
                const millwatch::identify::FitOptions& options) {
  const MeasuredRevolution measured = millwatch::test::finer_window(truth);
  model::ModelConfig start = truth;
  start.effects.runout.offset_um = 0.0;
  WindowFitter fitter(start, millwatch::test::ideal_lowpass, options);
  const FitResult first = fitter.fit(measured);
  if (!first.ok) {
    state.SkipWithError(first.message.c_str());
    return;
  }
  long evaluations = 0;
  for (auto _ : state) {
    const FitResult r = fitter.fit(measured, from_previous ? &first : nullptr);
    evaluations += r.evaluations;
    benchmark::DoNotOptimize(r.rho_um.value);
  }
  state.counters["evaluations"] =
      benchmark::Counter(static_cast<double>(evaluations), benchmark::Counter::kAvgIterations);
}

void fit(benchmark::State& state, int flutes, model::Operation op, bool from_previous,
         bool systematic = true) {
  millwatch::identify::FitOptions options;
  options.systematic = systematic;
  fit_window(state, cut(flutes, op), from_previous, options);
}

void BM_FitTwoFluteSlot(benchmark::State& s) {
  fit(s, 2, model::Operation::kSlot, false);
}
void BM_FitFourFluteDown(benchmark::State& s) {
  fit(s, 4, model::Operation::kDownMilling, false);
}
void BM_FitTwoFluteSlotFromPrevious(benchmark::State& s) {
  fit(s, 2, model::Operation::kSlot, true);
}
// Without the systematic variants: the continuous identifier's windows between two refits of
// the variants (identify::Identifier, every 10th window or on a change).
void BM_FitTwoFluteSlotWithoutVariants(benchmark::State& s) {
  fit(s, 2, model::Operation::kSlot, false, false);
}
void BM_FitTwoFluteSlotFromPreviousWithoutVariants(benchmark::State& s) {
  fit(s, 2, model::Operation::kSlot, true, false);
}
/// The full model of the demo (config/demo.json: [000]'s cp-Ti power law with trochoidal
/// path, multi-pass, minimum chip, accumulation, deflection, helix, dynamometer): the
/// coefficients are no longer linear (the deflection balance), so Levenberg–Marquardt carries
/// them; fitted from the previous window's result as the continuous identifier does.
void fit_full_model(benchmark::State& state, bool from_previous) {
  model::ModelConfig truth;  // every effect on
  truth.tool.diameter_mm = 0.4;
  truth.process.radial_depth_mm = 0.4;
  truth.process.feed_per_tooth_um = 4.0;
  truth.process.axial_depth_mm = 0.04;
  truth.effects.runout.offset_um = 1.82;
  truth.effects.runout.angle_rad = 0.58;
  truth.effects.min_chip.h_min_um = 0.2;
  truth.effects.deflection.stiffness_N_per_um = 0.47;
  truth.effects.helix_lag.discs = 10;
  fit_window(state, truth, from_previous, millwatch::identify::FitOptions{});
}
void BM_FitFullModel(benchmark::State& s) {
  fit_full_model(s, false);
}
void BM_FitFullModelFromPrevious(benchmark::State& s) {
  fit_full_model(s, true);
}

/// A recorded cut in memory: what the dynamometer read.
struct Recorded {
  millwatch::monitor::MonitorConfig config;  // as commanded (the fitter's view)
  std::vector<double> fx, fy, fz;
};

Recorded record(double feed_um) {
  millwatch::sim::Scenario s;
  s.sample_rate_hz = 50000.0;
  s.duration_s = 1.0;
  s.seed = static_cast<std::uint64_t>(10 * feed_um);
  s.model = cut(2, model::Operation::kSlot);
  s.model.tool.diameter_mm = 0.4;
  s.model.process.radial_depth_mm = 0.4;
  s.model.process.feed_per_tooth_um = feed_um;
  model::set_effect(s.model, "dynamometer", true);
  s.model.effects.dynamometer.natural_hz = {4500.0, 4600.0, 6000.0};
  s.spindle.actual_rpm = 0.99 * s.model.process.spindle_rpm;
  s.noise.enabled = true;
  s.noise.sigma_N = {0.015, 0.015, 0.015};
  Recorded r;
  r.config.model = s.model;
  r.config.sample_rate_hz = s.sample_rate_hz;
  r.config.lockstep = false;
  r.config.model.effects.runout.offset_um = 0.0;
  s.model.effects.helix_lag.discs = 20;
  s.model.resolution.steps_per_rev = 1440;
  millwatch::sim::CutSimulator simulator(s);
  const auto n = static_cast<std::size_t>(simulator.total_samples());
  std::vector<double> t(n);
  r.fx.resize(n);
  r.fy.resize(n);
  r.fz.resize(n);
  simulator.next_block(t, r.fx, r.fy, r.fz);
  return r;
}

void BM_CalibrateFiveOneSecondCuts(benchmark::State& state) {
  std::vector<Recorded> cuts;
  for (const double f : {3.0, 4.0, 5.0, 6.0, 8.0}) {
    cuts.push_back(record(f));
  }
  for (auto _ : state) {
    std::vector<millwatch::identify::CalibrationCut> input;
    for (const Recorded& r : cuts) {
      millwatch::identify::CutWindows windows;
      millwatch::monitor::Pipeline p(r.config, windows);
      constexpr std::size_t kBlock = 1000;
      for (std::size_t i = 0, seq = 0; i < r.fx.size(); i += kBlock, ++seq) {
        const std::size_t n = std::min(kBlock, r.fx.size() - i);
        p.process({static_cast<std::int64_t>(1e6 * static_cast<double>(i) / 50000.0),
                   static_cast<std::int64_t>(seq), 50000.0, std::span(r.fx).subspan(i, n),
                   std::span(r.fy).subspan(i, n), std::span(r.fz).subspan(i, n)});
      }
      p.finish();
      const auto filter = p.filter();
      input.push_back({"cut", r.config.model, [filter](double hz) { return filter.response(hz); },
                       windows.windows()});
    }
    const millwatch::identify::CalibrationResult result = millwatch::identify::calibrate(input);
    if (!result.ok) {
      state.SkipWithError(result.message.c_str());
      return;
    }
    benchmark::DoNotOptimize(result.joint.fit.coefficients.front().value);
    state.counters["evaluations"] = static_cast<double>(result.joint.fit.evaluations);
  }
}

BENCHMARK(BM_FitTwoFluteSlot)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FitTwoFluteSlotWithoutVariants)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FitTwoFluteSlotFromPreviousWithoutVariants)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FitFourFluteDown)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FitTwoFluteSlotFromPrevious)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FitFullModel)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FitFullModelFromPrevious)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CalibrateFiveOneSecondCuts)->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace

BENCHMARK_MAIN();
