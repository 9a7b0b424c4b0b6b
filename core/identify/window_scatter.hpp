#pragma once
// How far a cut's fitted windows agree on the runout, against the σ each window states. A
// window's σ comes from its own residual and Jacobian; where the force pins a direction poorly
// (ρ·sin γ with a helix, a flute that cuts nothing), a single window can state a small σ by
// chance while successive windows scatter far more (a 2-flute slot with a flute idle: ρ 1.9 to
// 11.7 µm from window to window, the last one 5.98 ± 0.68 µm). WindowScatter keeps the last
// kWindows fitted windows' ρ, γ and radius differences r_j − r_CE1 and gives, per quantity, the σ
// of one window about the cut's value from successive windows' differences
// (monitor::successive_scatter, as the alerts' estimate baseline: blind to a slow trend and to a
// single step). widened() states a window with each σ at least that scatter.

#include <cstddef>
#include <vector>

#include "core/identify/window_fit.hpp"

namespace millwatch::identify {

class WindowScatter {
 public:
  static constexpr std::size_t kWindows = 64;  ///< the newest windows kept
  static constexpr int kLeastWindows = 4;      ///< below this, no scatter is stated

  /// Records a fitted window (fit.ok; others are ignored). A window with another flute count
  /// than the ones before starts the record again.
  void add(const FitResult& fit);
  [[nodiscard]] int windows() const { return static_cast<int>(rho_um_.size()); }

  struct Scatter {
    int windows = 0;
    double rho_um = 0.0;
    double gamma_rad = 0.0;
    std::vector<double> radius_from_ce1_um;  ///< per flute (0 for CE1)
  };
  /// The scatter of the windows recorded (all 0 below kLeastWindows).
  [[nodiscard]] Scatter scatter() const;
  /// `fit` with the total σ of ρ, γ and each r_j − r_CE1 (and r_j) at least the windows'
  /// scatter; `widened_out` says whether any grew by more than half again.
  [[nodiscard]] FitResult widened(const FitResult& fit, bool& widened_out) const;

 private:
  std::vector<double> rho_um_, gamma_rad_;
  std::vector<std::vector<double>> radius_from_ce1_um_;  // [flute][window]
};

}  // namespace millwatch::identify
