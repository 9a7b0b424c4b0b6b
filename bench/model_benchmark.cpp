// Cost of the physics: the steady-state evaluator (plain model, lockstep model, full model,
// force basis, a lockstep-style rebuild at a new speed), the time-marching model (one revolution,
// an update after a parameter change) and the recorded-cut simulator's throughput.
//
//   build/release/bench/model_benchmark --benchmark_min_time=1

#include <benchmark/benchmark.h>

#include <array>
#include <complex>
#include <span>
#include <vector>

#include "core/model/milling_model.hpp"
#include "core/model/periodic_response.hpp"
#include "core/model/steady_state.hpp"
#include "core/signal/butterworth_lowpass.hpp"
#include "core/sim/cut_simulator.hpp"

namespace {

using millwatch::model::ModelConfig;

constexpr int kSteps = 720;

/// 2 flutes, 10 discs, 0.5° steps, every effect on.
ModelConfig full_model() {
  ModelConfig c;  // [000]'s cp-Ti case: runout, trochoid, multi-pass, min chip, accumulation,
                  // deflection and 10 helix discs are on by default
  c.resolution.steps_per_rev = kSteps;
  c.effects.helix_lag.discs = 10;
  c.effects.flank_wear.enabled = true;
  c.effects.flank_wear.wear_um = {5.0, 3.0};
  c.effects.dynamometer.enabled = true;
  return c;
}

/// [001]'s ploughed-area law on the full model: config/presets/alsi10mg_abeni2024.json's model
/// (0.789 mm, 2 flutes, slot, f_t 3 µm, a_p 0.25 mm, h_min 1.5 µm, deflection, the
/// dynamometer's resonance, 10 discs). The areas are walked over every pass of the cycle, and
/// with deflection solved again until they settle (or six times).
ModelConfig area_law_model() {
  ModelConfig c = full_model();
  c.effects.flank_wear.enabled = false;
  c.effects.dynamometer.natural_hz = {2145.0, 2192.0, 2500.0};
  c.tool.diameter_mm = 0.789;
  c.tool.helix_deg = 20.0;
  c.tool.edge_radius_um = 2.5;
  c.process.spindle_rpm = 31831.0;
  c.process.feed_per_tooth_um = 3.0;
  c.process.axial_depth_mm = 0.25;
  c.process.radial_depth_mm = 0.789;
  c.process.operation = millwatch::model::Operation::kSlot;
  c.effects.runout.offset_um = 1.0;
  c.effects.runout.angle_rad = -1.2;
  c.effects.min_chip.h_min_um = 1.5;
  c.effects.deflection.stiffness_N_per_um = 2.0;
  c.material.law = millwatch::model::ForceLawKind::kLinearEdge;
  auto& m = c.material.linear_edge;
  m.k_tc_N_per_mm2 = 1000.0;
  m.k_nc_N_per_mm2 = 420.0;
  m.k_ac_N_per_mm2 = 60.0;
  m.k_te_N_per_mm = m.k_ne_N_per_mm = m.k_ae_N_per_mm = 0.0;
  m.ploughing_area = true;
  m.k_tp_N_per_mm3 = 4000.0;
  m.k_np_N_per_mm3 = 6000.0;
  m.k_ap_N_per_mm3 = 500.0;
  return c;
}

/// [002]'s copper slot with chip accumulation: config/presets/copper_li2007.json's model (0.8 mm,
/// 2 flutes, helix 30°, 96,000 rpm, f_t 0.125 µm, a_p 0.02 mm, runout 1 µm, the minimum chip
/// 0.9 µm — 7.2 feeds — with accumulation, rigid, 10 discs): each slot is run pass by pass until
/// the material piled up below h_min repeats, looking back over 32 passes. Evaluated at 25,000 and
/// 25,001 rpm as the others (steady_state()): the speed reaches only the dynamometer's response,
/// off here.
ModelConfig copper_model() {
  ModelConfig c;
  c.resolution.steps_per_rev = kSteps;
  c.tool.diameter_mm = 0.8;
  c.tool.flutes = 2;
  c.tool.helix_deg = 30.0;
  c.tool.edge_radius_um = 2.0;
  c.process.operation = millwatch::model::Operation::kSlot;
  c.process.spindle_rpm = 96000.0;
  c.process.feed_per_tooth_um = 0.125;
  c.process.axial_depth_mm = 0.02;
  c.process.radial_depth_mm = 0.8;
  c.material.law = millwatch::model::ForceLawKind::kLinearEdge;
  auto& m = c.material.linear_edge;
  m.k_tc_N_per_mm2 = 1600.0;
  m.k_nc_N_per_mm2 = 900.0;
  m.k_ac_N_per_mm2 = 150.0;
  m.k_te_N_per_mm = 2.0;
  m.k_ne_N_per_mm = 4.0;
  m.k_ae_N_per_mm = 0.5;
  m.a_t_Nmm = 114.7;
  m.b_t = 0.5;
  m.a_n_Nmm = 183.3;
  m.b_n = 0.5;
  m.a_a_Nmm = 21.3;
  m.b_a = 0.5;
  c.effects.runout.enabled = true;
  c.effects.runout.offset_um = 1.0;
  c.effects.runout.angle_rad = 0.5;
  c.effects.trochoidal.enabled = true;
  c.effects.multi_pass.enabled = true;
  c.effects.min_chip.enabled = true;
  c.effects.min_chip.h_min_um = 0.9;
  c.effects.accumulation.enabled = true;
  c.effects.deflection.enabled = false;
  c.effects.helix_lag.enabled = true;
  c.effects.helix_lag.discs = 10;
  c.effects.dynamometer.enabled = false;
  return c;
}

/// The plain model: circular path, one regime, rigid, sharp; helix lag on with 5 discs.
ModelConfig plain_model() {
  ModelConfig c = millwatch::model::without_effects(ModelConfig{});
  c.effects.helix_lag.enabled = true;
  c.effects.helix_lag.discs = 5;
  return c;
}

/// The lockstep's model: the plain model with runout.
ModelConfig lockstep_model() {
  ModelConfig c = plain_model();
  c.effects.runout.enabled = true;
  return c;
}

void steady_state(
    benchmark::State& state, const ModelConfig& c,
    millwatch::model::SteadyStateOutput output = millwatch::model::SteadyStateOutput::kMean) {
  millwatch::model::SteadyStateWorkspace ws(c, kSteps);
  double rpm = 25000.0;
  for (auto _ : state) {
    // A new speed each time: the slots are solved afresh; the chip tables and the immersion
    // grid, which the speed alone does not move, are kept (the lockstep's rebuild also rescales
    // the feed per tooth, which remakes the chip tables: BM_LockstepRebuild*).
    rpm = rpm == 25000.0 ? 25001.0 : 25000.0;
    const auto& s = millwatch::model::evaluate_steady_state(c, rpm, kSteps, ws, output);
    benchmark::DoNotOptimize(s.mean.fx_N.data());
  }
  const auto& s = ws.result();
  state.counters["cycle_revs"] = s.cycle_revolutions;
  state.counters["passes"] = static_cast<double>(s.stats.passes);
  state.counters["sweeps"] = s.stats.area_sweeps;
  state.counters["longest_transient"] = s.stats.longest_transient_revolutions;
}

void BM_SteadyStatePlain(benchmark::State& state) {
  steady_state(state, plain_model());
}
BENCHMARK(BM_SteadyStatePlain)->Unit(benchmark::kMicrosecond);

void BM_SteadyStatePlainWithRunout(benchmark::State& state) {
  steady_state(state, lockstep_model());
}
BENCHMARK(BM_SteadyStatePlainWithRunout)->Unit(benchmark::kMicrosecond);

void BM_SteadyStateFull(benchmark::State& state) {
  steady_state(state, full_model());
}
BENCHMARK(BM_SteadyStateFull)->Unit(benchmark::kMicrosecond);

void BM_SteadyStateAreaLaw(benchmark::State& state) {
  steady_state(state, area_law_model());
}
BENCHMARK(BM_SteadyStateAreaLaw)->Unit(benchmark::kMicrosecond);

void BM_SteadyStateCopper(benchmark::State& state) {
  steady_state(state, copper_model());
}
BENCHMARK(BM_SteadyStateCopper)->Unit(benchmark::kMicrosecond);

/// The same with the accumulation cycle materialised (what the simulator asks for).
void BM_SteadyStateFullWithCycle(benchmark::State& state) {
  steady_state(state, full_model(), millwatch::model::SteadyStateOutput::kMeanAndCycle);
}
BENCHMARK(BM_SteadyStateFullWithCycle)->Unit(benchmark::kMicrosecond);

/// A fitter's trial: new runout, same speed (the chip tables are rebuilt, as for any new
/// geometry).
void BM_SteadyStateFullAfterRunoutChange(benchmark::State& state) {
  ModelConfig c = full_model();
  millwatch::model::SteadyStateWorkspace ws(c, kSteps);
  int i = 0;
  for (auto _ : state) {
    c.effects.runout.offset_um = 1.5 + 0.001 * (i++ % 100);
    benchmark::DoNotOptimize(millwatch::model::evaluate_steady_state(
                                 c, 25000.0, kSteps, ws, millwatch::model::SteadyStateOutput::kMean)
                                 .mean.fx_N.data());
  }
}
BENCHMARK(BM_SteadyStateFullAfterRunoutChange)->Unit(benchmark::kMicrosecond);

/// The same on a rigid tool axis: one chip table per disc (10) instead of one.
void BM_SteadyStateFullAfterRunoutChangeRigidAxis(benchmark::State& state) {
  ModelConfig c = full_model();
  c.effects.runout.helix = millwatch::model::RunoutHelix::kRigidAxis;
  millwatch::model::SteadyStateWorkspace ws(c, kSteps);
  int i = 0;
  for (auto _ : state) {
    c.effects.runout.offset_um = 1.5 + 0.001 * (i++ % 100);
    benchmark::DoNotOptimize(millwatch::model::evaluate_steady_state(
                                 c, 25000.0, kSteps, ws, millwatch::model::SteadyStateOutput::kMean)
                                 .mean.fx_N.data());
  }
}
BENCHMARK(BM_SteadyStateFullAfterRunoutChangeRigidAxis)->Unit(benchmark::kMicrosecond);

/// The six linear-edge basis waveforms of the lockstep model (rigid, so the basis is valid).
void BM_ForceBasisLinearEdge(benchmark::State& state) {
  ModelConfig c = lockstep_model();
  c.material.law = millwatch::model::ForceLawKind::kLinearEdge;
  millwatch::model::SteadyStateWorkspace ws(c, kSteps);
  for (auto _ : state) {
    const auto& b = millwatch::model::evaluate_force_basis(c, 25000.0, kSteps, ws);
    benchmark::DoNotOptimize(b.unit[0].fx_N.data());
  }
}
BENCHMARK(BM_ForceBasisLinearEdge)->Unit(benchmark::kMicrosecond);

/// What Lockstep::set_spindle_hz pays for a new measured speed: the configuration at that speed
/// (feed rate fixed), the steady state, and the monitor's causal Butterworth low-pass applied to
/// each axis as its periodic steady state (harmonic k times H(k·f)).
void lockstep_rebuild(benchmark::State& state, const ModelConfig& commanded) {
  ModelConfig at_speed = commanded;
  millwatch::model::SteadyStateWorkspace ws(commanded, kSteps);
  millwatch::model::PeriodicResponse response(kSteps);
  const auto design = millwatch::signal::ButterworthDesign::lowpass(333300.0, 3300.0, 4);
  std::array<std::vector<double>, 3> filtered;
  for (auto& f : filtered) {
    f.resize(kSteps);
  }
  std::vector<std::complex<double>> gains(static_cast<std::size_t>(response.harmonics()));
  double rpm = 25252.0;
  for (auto _ : state) {
    rpm = rpm == 25252.0 ? 25300.0 : 25252.0;
    millwatch::model::at_actual_speed(commanded, rpm, at_speed);
    const auto& s = millwatch::model::evaluate_steady_state(
        at_speed, rpm, kSteps, ws, millwatch::model::SteadyStateOutput::kMean);
    millwatch::model::harmonic_gains([&](double f) { return design.response(f); }, rpm / 60.0,
                                     millwatch::model::ResponseUse::kComplex, gains);
    const std::array<const std::vector<double>*, 3> axes = {&s.mean.fx_N, &s.mean.fy_N,
                                                            &s.mean.fz_N};
    for (std::size_t a = 0; a < 3; ++a) {
      std::copy(axes[a]->begin(), axes[a]->end(), filtered[a].begin());
      response.apply(filtered[a], gains);
    }
    benchmark::DoNotOptimize(filtered[0].data());
  }
}

void BM_LockstepRebuildPlainWithRunout(benchmark::State& state) {
  lockstep_rebuild(state, lockstep_model());
}
BENCHMARK(BM_LockstepRebuildPlainWithRunout)->Unit(benchmark::kMicrosecond);

void BM_LockstepRebuildFull(benchmark::State& state) {
  lockstep_rebuild(state, full_model());
}
BENCHMARK(BM_LockstepRebuildFull)->Unit(benchmark::kMicrosecond);

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

void BM_ModelUpdateAfterRunoutChangeRigidAxis(benchmark::State& state) {
  ModelConfig c = full_model();
  c.effects.runout.helix = millwatch::model::RunoutHelix::kRigidAxis;
  millwatch::model::MillingModel model(c);
  int i = 0;
  for (auto _ : state) {
    c.effects.runout.offset_um = 1.5 + 0.001 * (i++ % 100);
    model.update(c);
  }
}
BENCHMARK(BM_ModelUpdateAfterRunoutChangeRigidAxis)->Unit(benchmark::kMicrosecond);

/// The simulator's samples per second. With flank wear growing over the record the model is
/// evaluated again every revolution (the conditions change); steady conditions evaluate once.
void simulator_throughput(benchmark::State& state, bool growing_wear) {
  millwatch::sim::Scenario s;
  s.model = full_model();
  s.sample_rate_hz = static_cast<double>(state.range(0));
  s.duration_s = 0.25;
  s.spindle.actual_rpm = 25252.0;
  s.noise.enabled = true;
  s.quantisation.enabled = true;
  s.hum.enabled = true;
  s.drift.enabled = true;
  s.wear.enabled = growing_wear;
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

void BM_SimulatorThroughput(benchmark::State& state) {
  simulator_throughput(state, true);
}
BENCHMARK(BM_SimulatorThroughput)->Arg(50000)->Arg(333300)->Unit(benchmark::kMillisecond);

void BM_SimulatorThroughputSteady(benchmark::State& state) {
  simulator_throughput(state, false);
}
BENCHMARK(BM_SimulatorThroughputSteady)->Arg(50000)->Arg(333300)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
