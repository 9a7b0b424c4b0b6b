// Cost of one identification: a 30-revolution window's synchronous average (a 2-flute slot with
// runout, 4 flutes down-milling), fitted from scratch and from the previous window's result.

#include <benchmark/benchmark.h>

#include <complex>

#include "core/identify/window_fit.hpp"
#include "core/model/steady_state.hpp"

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

MeasuredRevolution measured_from(const model::ModelConfig& truth) {
  model::ModelConfig fine = truth;
  fine.effects.helix_lag.discs = 20;
  model::SteadyStateWorkspace ws;
  const auto& ss = model::evaluate_steady_state(fine, truth.process.spindle_rpm, 1440, ws);
  MeasuredRevolution m;
  m.force_N = {ss.mean.fx_N, ss.mean.fy_N, ss.mean.fz_N};
  m.spindle_rpm = truth.process.spindle_rpm;
  m.revolutions = 30;
  m.shared_bins = false;
  return m;
}

void fit(benchmark::State& state, int flutes, model::Operation op, bool from_previous,
         bool systematic = true) {
  const model::ModelConfig truth = cut(flutes, op);
  const MeasuredRevolution measured = measured_from(truth);
  model::ModelConfig start = truth;
  start.effects.runout.offset_um = 0.0;
  millwatch::identify::FitOptions options;
  options.systematic = systematic;
  WindowFitter fitter(
      start, [](double hz) { return std::complex<double>(hz < 3300.0 ? 1.0 : 0.0, 0.0); }, options);
  const FitResult first = fitter.fit(measured);
  long evaluations = 0;
  for (auto _ : state) {
    const FitResult r = fitter.fit(measured, from_previous ? &first : nullptr);
    evaluations += r.evaluations;
    benchmark::DoNotOptimize(r.rho_um.value);
  }
  state.counters["evaluations"] =
      benchmark::Counter(static_cast<double>(evaluations), benchmark::Counter::kAvgIterations);
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
BENCHMARK(BM_FitTwoFluteSlot)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FitTwoFluteSlotWithoutVariants)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FitTwoFluteSlotFromPreviousWithoutVariants)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FitFourFluteDown)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FitTwoFluteSlotFromPrevious)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
