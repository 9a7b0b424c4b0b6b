#pragma once
// The classic calibration of the linear-edge law from the mean force ([000] Sect. 5, [001]
// Table 4; Altintas, Manufacturing Automation, the average-force method): cuts at several feeds
// per tooth f_t and otherwise equal engagement, the mean force per revolution of each against
// f_t, a straight line per axis, the coefficients from the slopes and intercepts.
//
// Derivation in this project's frame (model_config.hpp: x feed, y cross-feed, z from the work
// towards the spindle; immersion θ = 0 on +y, π/2 straight ahead; forces ON THE TOOL). With the
// circular path's chip h = f_t·sin θ, no runout, and the linear-edge law ([002] eq 18)
//   dF_t = (K_tc·h + K_te)·dz,  dF_n = (K_nc·h + K_ne)·dz,  dF_a = (K_ac·h + K_ae)·dz
// projected as the model does ([000] eq 7)
//   F_x = −F_t·cos θ − F_n·sin θ,  F_y = F_t·sin θ − F_n·cos θ,  F_z = F_a,
// the mean over a revolution of N flutes engaged over [θ_s, θ_e] at axial depth a is
//   F̄_x/(N·a) = −[(K_tc·I_sc + K_nc·I_ss)·f_t + K_te·I_c + K_ne·I_s] / 2π
//   F̄_y/(N·a) =  [(K_tc·I_ss − K_nc·I_sc)·f_t + K_te·I_s − K_ne·I_c] / 2π
//   F̄_z/(N·a) =  [K_ac·I_s·f_t + K_ae·(θ_e − θ_s)] / 2π
// with I_sc = ∫sin θ cos θ dθ, I_ss = ∫sin²θ dθ, I_c = ∫cos θ dθ, I_s = ∫sin θ dθ over [θ_s, θ_e]
// (the helix lag does not change a mean over a whole revolution). A slot (θ ∈ [0, π]: I_sc = 0,
// I_ss = π/2, I_c = 0, I_s = 2) gives Altintas' slot formulas in this frame:
//   F̄_x = −(N·a·K_nc/4)·f_t − N·a·K_ne/π,   F̄_y = (N·a·K_tc/4)·f_t + N·a·K_te/π,
//   F̄_z = (N·a·K_ac/π)·f_t + N·a·K_ae/2
// so K_tc = 4·slope_y, K_nc = −4·slope_x, K_te = π·icpt_y, K_ne = −π·icpt_x, K_ac = π·slope_z,
// K_ae = 2·icpt_z for the lines of F̄/(N·a) against f_t. For another engagement the two in-plane
// lines give 2×2 systems (determinants I_sc² + I_ss² and I_c² + I_s², never 0).
//
// Each line is fitted by least squares to one point per cut (F̄/(N·a) against the cut's actual
// chip load, mm); σ of slope and intercept from the residual, s² = RSS/(n − 2), mapped to the
// coefficients through the 2×2 solve (the axes taken as independent). Hence at least three cuts
// at two or more feeds.
//
// What it cannot know. The mean force is where the charge amplifiers' offset and drift live:
// the method needs channels tared just before each cut. Runout moves chip between the flutes,
// which leaves the mean alone only where every flute cuts (Σ_j (r_j − r_{j−1}) = 0): near a
// slot's walls, and over much of a down-milling arc, f_t·sin θ falls below the radius
// differences, the short flute cuts nothing there while the long one still cuts its excess, and
// the mean grows faster than linearly as f_t falls. The lines bend, and the coefficients come
// out biased far beyond their σ (which is the scatter about the lines only): on simulated
// sweeps with ρ = 1.2–1.5 µm K_nc came out 1.7–2.2 times the truth (tests/identify/
// calibration_test.cpp; the README's Calibration table). The trochoidal path, a minimum chip
// thickness and deflection bend them too. The model fit (window_fit.hpp, fit_cuts) accounts for
// all of these; this method is printed beside it as the reference practice, not as a check.

#include <array>
#include <string>
#include <vector>

#include "core/identify/window_fit.hpp"
#include "core/model/model_config.hpp"

namespace millwatch::identify {

/// One cut: its engagement and its mean force on the tool per revolution (model frame, N).
struct MeanForceCut {
  model::ModelConfig model;   ///< the cut's tool and engagement (process.operation, depths)
  double chip_load_um = 0.0;  ///< actual feed per tooth (commanded f_t · n_cmd / n)
  std::array<double, 3> mean_force_N{};
  std::array<bool, 3> measured = {true, true, false};  ///< axes with a mean force
};

/// A straight line F̄/(N·a) = slope·f_t + intercept for one axis (f_t in mm: N/mm² and N/mm).
struct ForceLine {
  bool fitted = false;
  double slope_N_per_mm2 = 0.0, slope_std_N_per_mm2 = 0.0;
  double intercept_N_per_mm = 0.0, intercept_std_N_per_mm = 0.0;
  double residual_rms_N_per_mm = 0.0;
};

struct AverageForceRegression {
  bool ok = false;
  std::string message;                 ///< why not (every value absent then)
  std::array<ForceLine, 3> lines{};    ///< fx, fy, fz
  std::vector<Estimate> coefficients;  ///< k_tc_N_per_mm2 … k_ae_N_per_mm (linear-edge names)
  double immersion_start_rad = 0.0, immersion_exit_rad = 0.0;
  int cuts = 0;
  std::string note =
      "from the mean force: valid only with channels tared before each cut (no amplifier "
      "offset or drift); assumes a circular chip path and every flute cutting its share "
      "(runout biases it)";
};

/// Immersion [θ_s, θ_e] of a cut (model_config.hpp convention, [000] eq 28).
std::array<double, 2> immersion_rad(const model::ModelConfig& model);

/// The regression over the cuts. Not ok (with the reason) for fewer than three cuts, fewer than
/// two distinct feeds, or cuts that differ in engagement (operation or a_e/D) or flute count.
AverageForceRegression average_force_regression(const std::vector<MeanForceCut>& cuts);

}  // namespace millwatch::identify
