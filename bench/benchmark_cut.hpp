#pragma once
// The simulated cut the pipeline benchmarks and scripts/daemon_load.sh's feeder run on: the
// default [000] cut with sensor noise and quantisation, at a sample rate, length and actual
// spindle speed, simulated whole into memory.

#include <vector>

#include "core/sim/cut_simulator.hpp"

namespace millwatch::bench {

struct BenchmarkCut {
  double sample_rate_hz = 0.0;
  std::vector<double> t, fx, fy, fz;  ///< s, N (the dynamometer's reading)
};

/// The default [000] cut with sensor noise and quantisation.
inline sim::Scenario benchmark_scenario(double sample_rate_hz, double duration_s,
                                        double actual_rpm) {
  sim::Scenario s;
  s.sample_rate_hz = sample_rate_hz;
  s.duration_s = duration_s;
  s.spindle.actual_rpm = actual_rpm;
  s.noise.enabled = true;
  s.quantisation.enabled = true;
  return s;
}

/// `s` simulated whole.
inline BenchmarkCut simulate_cut(const sim::Scenario& s) {
  sim::CutSimulator simulator(s);
  BenchmarkCut r;
  r.sample_rate_hz = s.sample_rate_hz;
  const auto n = static_cast<std::size_t>(simulator.total_samples());
  for (auto* v : {&r.t, &r.fx, &r.fy, &r.fz}) {
    v->resize(n);
  }
  simulator.next_block(r.t, r.fx, r.fy, r.fz);
  return r;
}

/// The default cut (noise and quantisation on) at a rate, length and actual speed.
inline BenchmarkCut simulate_benchmark_cut(double sample_rate_hz, double duration_s,
                                           double actual_rpm) {
  return simulate_cut(benchmark_scenario(sample_rate_hz, duration_s, actual_rpm));
}

}  // namespace millwatch::bench
