// Cost of a full diagnosis (millwatch issue 8, item 6: a 1 s cut at 50 kHz in under 30 s on one
// core): a simulated cut with a hidden runout and a spindle running 1 % slow, diagnosed from the
// plain model — every candidate of the catalogue scored at every step, the winners refitted with
// their systematic uncertainty, the localisation and the plots' data of every stage.

#include <benchmark/benchmark.h>

#include "core/diagnose/diagnosis.hpp"
#include "tests/support/hidden_effect_cut.hpp"

namespace {

namespace diagnose = millwatch::diagnose;

void BM_DiagnoseOneSecondAt50kHz(benchmark::State& state) {
  const auto cut =
      millwatch::test::hidden_effect_cut({"runout", "spindle_speed_error"}, {}, 1.0, 50000.0);
  diagnose::Diagnosis d;
  for (auto _ : state) {
    d = diagnose::diagnose(cut.record, cut.start);
    benchmark::DoNotOptimize(d);
  }
  state.counters["effects_named"] = static_cast<double>(d.named_effects.size());
  state.counters["samples"] = static_cast<double>(cut.record.force_N[0].size());
  state.counters["final_over_floor_x"] =
      d.steps.empty() ? 0.0 : d.steps.back().residual_rms_N[0] / d.noise_floor_N[0];
  state.SetLabel(d.verdict.substr(0, 60));
}
BENCHMARK(BM_DiagnoseOneSecondAt50kHz)->Unit(benchmark::kSecond)->Iterations(1);

void BM_DiagnoseNegativeControl(benchmark::State& state) {
  const auto cut = millwatch::test::hidden_effect_cut({}, {}, 1.0, 50000.0);
  diagnose::Diagnosis d;
  for (auto _ : state) {
    d = diagnose::diagnose(cut.record, cut.start);
    benchmark::DoNotOptimize(d);
  }
  state.counters["effects_named"] = static_cast<double>(d.named_effects.size());
}
BENCHMARK(BM_DiagnoseNegativeControl)->Unit(benchmark::kSecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
