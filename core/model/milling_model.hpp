#pragma once
// The mechanistic micro-milling force model, marched revolution by revolution.
//
// Per spindle-angle step φ_k, axial disc i and flute j ([000] Fig. 9 flow):
//   1. rigid chip h_r = min over the previous passes n of (g_{j,n}(φ_k − lag_i) + e_n), where
//      g is the geometric chip against pass n (chip_geometry.hpp; [000] eqs 9-20) and e_n how
//      far pass n's real surface lies behind its rigid path: its deflection leftover δh, or
//      "did not cut" when it only ploughed (accumulation). This is the material-conserving
//      reading of [000] eqs 22-25 / [002] eqs 11-12 (physics-notes).
//   2. deflection ([000] eqs 21-23): F_n(h)·dz = (k_n/K)·(h_r − h) solved for the cut chip h.
//   3. regime ([000] eq 5, [002] eqs 17-18): ploughing coefficients when h < h_min; with
//      accumulation such a pass removes nothing and its chip adds to the next pass.
//   4. forces on the tool, projected by [000] eq 7 at the disc's immersion and summed over discs
//      and flutes ([000] eq 8); flank-wear rubbing adds K_w·VB·dz per engaged element.
//   5. dynamometer dynamics, if on, filter the summed forces with state carried across steps.
// Helix lag ([000] eqs 2-4, 6): disc i (i = 0..K−1 from the tip, thickness dz = a_p/K) trails
// the tool tip by lag_i = (i + ½)·β/K, β = arccos((2R² − a_p²·tan²λ)/(2R²)); we take each disc's
// midpoint where [000] eq 2 takes its top edge. Disc i reads its chip tables at φ − lag_i. With
// runout and helix "rigid_axis" each disc has its own tables, for the runout angle γ + lag_i its
// edge sees (the tool axis is offset rigidly; γ holds at the tip); with "tip_pattern" (the
// default) every disc reads the tip's tables, [000] eqs 1-2 as printed (model_config.hpp
// RunoutHelix, chip_geometry.hpp "Discs").
//
// Set up once per configuration (allocates); step_revolution() then allocates nothing.

#include <span>
#include <vector>

#include "core/model/chip_geometry.hpp"
#include "core/model/dynamometer.hpp"
#include "core/model/force_law.hpp"
#include "core/model/model_config.hpp"

namespace millwatch::model {

/// One revolution of force on the tool (N): index k is spindle angle φ_k = 2πk/steps.
struct ForceWaveform {
  std::vector<double> fx_N;
  std::vector<double> fy_N;
  std::vector<double> fz_N;
};

class MillingModel {
 public:
  /// @throws config::ConfigError if the configuration is invalid.
  explicit MillingModel(const ModelConfig& config);

  /// Applies a changed configuration (spindle speed, feed, runout, wear, coefficients...). The
  /// cut's state is kept when the discretisation (flutes, steps, discs, passes) is unchanged;
  /// then nothing is allocated. Otherwise the state is reset.
  void update(const ModelConfig& config);

  /// Forgets the cut's history: every earlier pass is taken to have cut along its rigid path.
  void reset();

  /// Advances the cut by one revolution; forces() then holds that revolution.
  void step_revolution();

  /// Steps revolutions until the force of one revolution repeats the previous one (at least
  /// settling_revolutions(), at most 150: accumulation patterns spanning several revolutions
  /// never repeat revolution to revolution), or exactly `revolutions` when > 0.
  /// @param tolerance largest change between two revolutions, relative to the peak force
  void warm_up(int revolutions = 0, double tolerance = 1e-6);

  [[nodiscard]] const ForceWaveform& forces() const { return forces_; }
  /// Chip (µm) that flute j engaged at step k of the last revolution, at the bottom disc (after
  /// deflection; zero out of contact).
  [[nodiscard]] double chip_um(int flute, int step) const {
    return chip_[static_cast<std::size_t>(flute * steps_ + step)];
  }
  /// Whether that pass removed material (false while it only ploughed, with accumulation on).
  [[nodiscard]] bool removed(int flute, int step) const {
    return removed_[static_cast<std::size_t>(flute * steps_ + step)] != 0;
  }
  [[nodiscard]] int steps_per_rev() const { return steps_; }
  [[nodiscard]] int flutes() const { return flutes_; }
  [[nodiscard]] int discs() const { return discs_; }
  [[nodiscard]] int passes_back() const { return passes_; }
  /// Time per angle step at the configured spindle speed.
  [[nodiscard]] double step_time_s() const { return step_time_s_; }
  [[nodiscard]] const ModelConfig& config() const { return config_; }
  [[nodiscard]] const ChipGeometry& chip_geometry() const { return geometry_; }
  /// Fewest revolutions warm_up(0) runs: enough to fill the pass history and let the
  /// dynamometer's free response decay.
  [[nodiscard]] int settling_revolutions() const;

 private:
  void derive(bool keep_state);
  void allocate();
  bool straddles_regime_jump(double h_rigid_um, double lo_log_um, double hi_log_um,
                             double wear_normal_N, double area_mm2) const;
  /// The cut chip h (µm) of [000] eq 22; also returns ln h in *log_h_um.
  double solve_deflection(double h_rigid_um, double guess_um, double wear_normal_N, double area_mm2,
                          double* log_h_um) const;
  void march_step(int k);

  /// What the chip tables depend on.
  struct GeometryKey {
    PathGeometry path;
    bool trochoidal = false;
    int passes = 0;
    int steps = 0;
    double window_from_rad = 0.0;
    double window_to_rad = 0.0;
    bool operator==(const GeometryKey& o) const {
      return path.radius_um == o.path.radius_um && path.feed_per_rad_um == o.path.feed_per_rad_um &&
             path.offset_um == o.path.offset_um &&
             path.offset_angle_rad == o.path.offset_angle_rad && trochoidal == o.trochoidal &&
             passes == o.passes && steps == o.steps && window_from_rad == o.window_from_rad &&
             window_to_rad == o.window_to_rad;
    }
  };

  ModelConfig config_;
  GeometryKey geometry_key_;
  ForceLaw law_;
  ChipGeometry geometry_;
  std::vector<double> pitch_rad_;
  int flutes_ = 0;
  int steps_ = 0;
  int discs_ = 1;
  int passes_ = 1;
  double d_phi_rad_ = 0.0;
  double dz_mm_ = 0.0;
  double step_time_s_ = 0.0;
  double disc_stiffness_N_per_um_ = 0.0;
  double h_min_um_ = 0.0;
  double engage_from_rad_ = 0.0;
  double engage_to_rad_ = 0.0;

  std::vector<int> pitch_steps_;   // ψ_j in grid steps
  std::vector<double> lag_steps_;  // lag_i in grid steps (fractional)
  std::vector<int> lag_floor_;     // floor(−lag_i): disc i reads the chip table from k + this...
  std::vector<double> lag_frac_;   // ...interpolating this far towards the next step
  std::vector<double> cos_phi_, sin_phi_;         // per step
  std::vector<double> cos_offset_, sin_offset_;   // per (disc, flute): ψ_j + lag_i
  std::vector<double> wear_t_N_, wear_n_N_;       // per flute, per disc element
  std::vector<double> tool_radius_mm_;            // per (disc, flute) cutting radius
  std::vector<double> disc_angles_rad_;           // per disc, added to γ (rigid axis), or empty
  std::vector<double> geometry_disc_angles_rad_;  // those the tables were made for

  std::vector<double> deficit_um_;      // per (disc, immersion step, pass ring slot)
  std::vector<int> ring_head_;          // per (disc, immersion step)
  std::vector<unsigned char> engaged_;  // per (disc, immersion step): inside the workpiece
  std::vector<double> area_cut_mm2_, area_plough_max_mm2_, area_total_prev_mm2_;
  std::vector<unsigned char> sheared_, in_contact_;
  std::vector<double> last_deflection_um_;  // per (disc, flute), Newton's starting point

  Dynamometer dynamometer_;
  ForceWaveform forces_;
  std::vector<double> previous_fx_N_, previous_fy_N_;  // warm_up's convergence check
  std::vector<double> chip_;
  std::vector<unsigned char> removed_;
};

}  // namespace millwatch::model
