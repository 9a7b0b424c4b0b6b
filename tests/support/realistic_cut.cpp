#include "tests/support/realistic_cut.hpp"

namespace millwatch::test {

sim::Scenario realistic_cut(const RealisticCut& k) {
  sim::Scenario s;
  s.sample_rate_hz = 50000.0;
  s.duration_s = k.duration_s;
  s.seed = k.seed;
  auto& m = s.model;
  m = model::without_effects(m);
  m.material.law = model::ForceLawKind::kLinearEdge;
  m.tool.flutes = k.flutes;
  m.tool.diameter_mm = k.diameter_mm;
  m.process.operation = k.operation;
  m.process.radial_depth_mm = k.radial_depth_mm;
  m.process.feed_per_tooth_um = k.feed_um;
  m.process.axial_depth_mm = 0.05;
  model::set_effect(m, "runout", true);
  m.effects.runout.offset_um = k.rho_um;
  m.effects.runout.angle_rad = k.gamma_rad;
  model::set_effect(m, "helix_lag", true);
  model::set_effect(m, "dynamometer", true);
  m.effects.dynamometer.natural_hz = {4500.0, 4600.0, 6000.0};
  s.spindle.actual_rpm = 0.99 * m.process.spindle_rpm;
  measure_like_a_real_cut(s);
  return s;
}

void measure_like_a_real_cut(sim::Scenario& s) {
  s.noise.enabled = true;
  s.noise.sigma_N = {0.015, 0.015, 0.015};
  s.quantisation.enabled = true;
  s.quantisation.bits = 16;
  s.quantisation.range_N = {327.68, 327.68, 327.68};  // 0.01 N steps
  s.model.resolution.steps_per_rev = 2880;
  s.model.effects.helix_lag.discs = 20;
}

}  // namespace millwatch::test
