#pragma once
// The simulated truth the identification tests fit: the linear-edge law ([002] eq 18, the
// model's default coefficients), runout, helix lag and the dynamometer's modes, sensor noise and
// 16-bit quantisation, the spindle 1 % slow, on a model finer than any the monitor builds
// (0.125° and 20 discs): a cut that differs from the fitted model as a real one would.

#include <cstdint>

#include "core/model/model_config.hpp"
#include "core/sim/scenario.hpp"

namespace millwatch::test {

struct RealisticCut {
  double duration_s = 0.4;
  std::uint64_t seed = 1;
  int flutes = 2;
  double diameter_mm = 0.4;
  model::Operation operation = model::Operation::kSlot;
  double radial_depth_mm = 0.4;
  double feed_um = 3.0;
  double rho_um = 0.0;     ///< runout offset
  double gamma_rad = 0.0;  ///< runout angle
};

/// The cut `k` at 50 kHz, 0.05 mm deep.
sim::Scenario realistic_cut(const RealisticCut& k);

/// What makes a simulated cut differ from the model fitted to it as a real one does, whatever
/// the cut: sensor noise 0.015 N, 16-bit quantisation in 0.01 N steps, and a truth finer than any
/// model the monitor builds (0.125° steps, 20 helix discs).
void measure_like_a_real_cut(sim::Scenario& s);

}  // namespace millwatch::test
