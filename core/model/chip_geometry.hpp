#pragma once
// Rigid-tool uncut chip thickness of each flute against the paths left by earlier passes.
//
// Flute j at spindle angle τ has immersion θ = τ − ψ_j. Its chip against the pass n flutes back
// (flute k = j − n mod N_z, which passed at the earlier spindle angle τ + Δ) is the signed
// distance, along the ray from the tool centre C(τ) through the flute tip, from the tip to where
// that earlier path crosses the ray (positive: the flute is outside the old path and cuts).
//
// Two interchangeable path models:
//   circular    h = v·Δψ_n·sin θ + r_j − r_k  (Kline/[002] eq 1 with runout), v = feed per radian
//   trochoidal  the exact crossing, found by Newton-Raphson on the cross product of the ray and
//               the old tip position ([002] eqs 2-10, [000] eqs 9-15 and 19), all in µm:
//                 C(τ) = (v·τ + ρ·sin(τ+γ), ρ·cos(τ+γ)),  Q(τ') = C(τ') + R·(sin(τ'−ψ_k),
//                 cos(τ'−ψ_k)) F(Δ) = (Q(τ+Δ) − C(τ)) × e(θ) = 0,      h = R − (Q(τ+Δ) − C(τ))·e(θ)
//               which is [000] eq 13 multiplied by cos θ (no singularity at θ = π/2; physics-notes)
//               and [000] eqs 16-18 in vector form (the same point, without the arctan of eq 18).
// The tables are computed once per configuration on the model's spindle-angle grid.
//
// Discs. With helix lag, disc i's edge trails the tip by lag_i; the model reads the tables at
// τ = φ − lag_i. A rigid offset of the tool axis (RunoutHelix::kRigidAxis, model_config.hpp)
// keeps the centre at ρ towards φ + γ = τ + (γ + lag_i), so disc i's chip is the tip's formula
// with the runout angle γ + lag_i (the feed's constant shift v·lag_i cancels in Q − C): one
// table per disc, each with its own radii r_{j,i} and edge shifts. Without per-disc angles (the
// tip's pattern for every disc, [000] eqs 1-2), or with ρ = 0, one table serves every disc.

#include <cmath>
#include <span>
#include <vector>

#include "core/model/flute_positions.hpp"

namespace millwatch::model {

/// Path parameters (µm, rad). Feed is along +x.
struct PathGeometry {
  double radius_um = 0.0;         ///< R, nominal tool radius
  double feed_per_rad_um = 0.0;   ///< v = f_t·N_z/(2π): feed advance per radian of spindle turn
  double offset_um = 0.0;         ///< ρ, runout offset
  double offset_angle_rad = 0.0;  ///< γ, runout angle
  bool operator==(const PathGeometry&) const = default;
};

struct TrochoidChip {
  double chip_um = 0.0;    ///< signed chip thickness
  double delta_rad = 0.0;  ///< Δ = τ' − τ (< 0): when the earlier flute crossed the ray
  int iterations = 0;
  bool converged = false;
};

/// Exact trochoidal chip of the flute at pitch ψ_j against the flute at pitch ψ_k that passed
/// roughly `delta_guess_rad` earlier (−Δψ_n, [000] eq 19; or a neighbouring solution).
TrochoidChip trochoidal_chip(const PathGeometry& path, double spindle_angle_rad, double psi_j_rad,
                             double psi_k_rad, double delta_guess_rad);

/// Circular-path chip with runout radii: h = v·Δψ·sin θ + r_j − r_k.
double circular_chip_um(const PathGeometry& path, double immersion_rad, double pitch_back_rad,
                        double radius_j_um, double radius_k_um);

/// Tables of the rigid chip of every flute against each of the previous `passes` passes, on a
/// uniform spindle-angle grid, per axial disc. Entry (j, n, k) of disc i: flute j at spindle
/// angle τ = 2πk/steps (of that disc's geometry) against the pass n back (n = 1..passes).
class ChipGeometry {
 public:
  /// Allocates when the sizes grow; otherwise refills in place. With `disc_angle_rad` given,
  /// room for one table per disc is reserved even while ρ = 0 lets one table serve them all.
  /// @param pitch_rad cumulative pitch ψ_j of each flute (ψ_0 = 0)
  /// @param window_from_rad, window_to_rad immersion range where the model may use the table;
  ///        outside it the (cheap) circular chip is stored instead of the trochoidal one.
  /// @param disc_angle_rad per disc, the angle added to path.offset_angle_rad (γ) for that
  ///        disc's geometry (lag_i for a rigid tool axis); empty: one geometry, γ, for every disc
  void configure(const PathGeometry& path, std::span<const double> pitch_rad, int passes,
                 int steps_per_rev, bool trochoidal, double window_from_rad = 0.0,
                 double window_to_rad = 7.0, std::span<const double> disc_angle_rad = {});

  /// Room for `discs` tables of this shape, so that later configure() calls of that shape
  /// allocate nothing (whether or not ρ > 0 then needs one table per disc).
  void reserve(int flutes, int passes, int steps_per_rev, int discs);

  /// Linear interpolation at a fractional grid position (wraps around the revolution).
  [[nodiscard]] double chip_um(int flute, int pass_back, double grid_position, int disc = 0) const {
    const double* row = row_of(flute, pass_back, disc);
    const double whole = std::floor(grid_position);
    const double frac = grid_position - whole;
    int k0 = static_cast<int>(whole) % steps_;
    if (k0 < 0) {
      k0 += steps_;
    }
    const int k1 = k0 + 1 == steps_ ? 0 : k0 + 1;
    return row[k0] + frac * (row[k1] - row[k0]);
  }
  /// The table row of flute j against the pass n back for disc i (steps() values).
  [[nodiscard]] const double* row(int flute, int pass_back, int disc = 0) const {
    return row_of(flute, pass_back, disc);
  }
  /// How far apart the rows of consecutive passes are: row(flute, n + 1, disc) is
  /// row(flute, n, disc) + pass_stride().
  [[nodiscard]] std::ptrdiff_t pass_stride() const { return steps_; }
  /// Table value at a grid index.
  [[nodiscard]] double at(int flute, int pass_back, int step, int disc = 0) const {
    return row_of(flute, pass_back, disc)[step];
  }

  [[nodiscard]] int passes() const { return passes_; }
  [[nodiscard]] int steps() const { return steps_; }
  [[nodiscard]] int flutes() const { return flutes_; }
  /// Discs given to configure (1 without disc angles).
  [[nodiscard]] int discs() const { return discs_; }
  /// Distinct tables held: discs() with per-disc angles and ρ > 0, else 1.
  [[nodiscard]] int tables() const { return tables_; }
  /// Newton iterations of the last configure (0 for the circular model), for benchmarks.
  [[nodiscard]] long newton_iterations() const { return newton_iterations_; }
  /// Cutting radius and angular shift of each flute at disc i (flute_positions.hpp with the
  /// disc's runout angle).
  [[nodiscard]] std::span<const FlutePosition> flutes_at(int disc = 0) const {
    return std::span<const FlutePosition>(flute_positions_)
        .subspan(static_cast<std::size_t>(table_of(disc) * flutes_),
                 static_cast<std::size_t>(flutes_));
  }

 private:
  [[nodiscard]] int table_of(int disc) const { return tables_ == 1 ? 0 : disc; }
  [[nodiscard]] const double* row_of(int flute, int pass_back, int disc) const {
    return table_.data() +
           static_cast<std::size_t>(((table_of(disc) * flutes_ + flute) * passes_ + pass_back - 1) *
                                    steps_);
  }
  /// Which grid steps of `flute` take the trochoid (in_window_): the flute's alone, the same for
  /// every pass back.
  void fill_window(std::span<const double> pitch_rad, int flute, bool trochoidal,
                   double window_from_rad, double window_to_rad);
  void fill_rows(const PathGeometry& path, std::span<const double> pitch_rad,
                 std::span<const double> disc_angle_rad, int flute, int pass_back);

  int flutes_ = 0;
  int passes_ = 0;
  int steps_ = 0;
  int discs_ = 1;
  int tables_ = 1;
  long newton_iterations_ = 0;
  std::vector<double> table_;
  std::vector<FlutePosition> flute_positions_;  // per (table, flute)
  std::vector<FlutePosition> scratch_positions_;
  /// One disc's row being filled and its Newton warm start.
  struct DiscRow {
    double* row = nullptr;
    double rj_um = 0.0, rk_um = 0.0;          // cutting radii of the flute and of the pass n back
    double sin_gamma = 0.0, cos_gamma = 1.0;  // of the disc's runout angle
    double last_rad = 0.0, slope_rad = 0.0;   // last crossing Δ and its change per step
    int known = 0;                            // entries behind it that converged (0..2)
  };
  std::vector<DiscRow> rows_;
  std::vector<double> circular_row_;  // v·Δψ_n·sin θ of the row being filled
  std::vector<unsigned char> in_window_;
  std::vector<double> cos_grid_, sin_grid_;  // cos, sin of 2πk/steps
};

/// Angle from the flute `n` passes back to flute j, summing pitch intervals (rad, > 0).
double pitch_back_rad(std::span<const double> pitch_rad, int flute, int pass_back);

}  // namespace millwatch::model
