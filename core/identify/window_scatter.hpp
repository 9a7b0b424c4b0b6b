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
//
// A slow trend it tells apart: ρ drifting while the radii hold. The force pins the radius
// differences (2ρ·cos γ for two flutes) and ρ·sin γ only through second-order effects, so an
// effect the model lacks moves ρ·sin γ first: a 2-flute slot whose flank wear grew from 0 to
// 3 µm (not modelled) took ρ from 0.84 to 3.05 µm (truth 0.8) while r_CE1 − r_CE2 held within
// 0.04 µm, and the last window stated ± 0.22 µm. When the newest quarter's median ρ differs from
// the oldest quarter's by more than 3σ of that difference (the scatter's), by more than the
// window's σ and by more than twice the largest drift of a radius difference (a change of the
// runout that the radii see would move them as much), widened() takes ρ's and γ's σ to at least
// their drifts — unless the windows kept mix fits on a contact edge (ρ stated as a bound) with
// others.

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

  static constexpr int kLeastDriftWindows = 16;  ///< below this, no drift is stated

  struct Scatter {
    int windows = 0;
    double rho_um = 0.0;
    double gamma_rad = 0.0;
    std::vector<double> radius_from_ce1_um;  ///< per flute (0 for CE1)
    /// The newest quarter's median minus the oldest quarter's (0 below kLeastDriftWindows).
    double rho_drift_um = 0.0;
    double gamma_drift_rad = 0.0;
    double radius_drift_um = 0.0;  ///< the largest |drift| of an r_j − r_CE1
    /// ρ's drift is beyond 3σ of its sampling error and twice the radii's (header comment).
    bool rho_drifts = false;
  };
  /// The scatter of the windows recorded (all 0 below kLeastWindows).
  [[nodiscard]] Scatter scatter() const;
  /// Which σ's widened() took up: by more than half again to the scatter, or to ρ's drift.
  struct Widening {
    bool by_scatter = false;
    bool by_drift = false;
  };
  /// `fit` with the total σ of ρ, γ and each r_j − r_CE1 (and r_j) at least the windows'
  /// scatter, and ρ's and γ's at least their drifts where ρ drifts beyond `fit`'s σ.
  [[nodiscard]] FitResult widened(const FitResult& fit, Widening& how) const;

 private:
  std::vector<double> rho_um_, gamma_rad_;
  std::vector<bool> on_edge_;                            // the window's fit was on a contact edge
  std::vector<std::vector<double>> radius_from_ce1_um_;  // [flute][window]
};

}  // namespace millwatch::identify
