#include "core/model/steady_state.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <numeric>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/model/chip_geometry.hpp"
#include "core/model/dynamometer.hpp"
#include "core/model/force_law.hpp"
#include "core/model/nearest_removal.hpp"
#include "core/model/periodic_response.hpp"

namespace millwatch::model {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kNoCut = kNoRemoval;  // a pass that removed nothing
constexpr int kMaxNewtonDim = 32;
constexpr int kMaxNewtonIterations = 12;
constexpr int kMaxAreaSweeps = 6;
/// A slot's state has repeated when every deficit agrees to this (µm).
constexpr double kDeficitTolerance_um = 1e-12;
/// Areas of two solutions agree (relative to the largest area) when the coupled solve stops.
constexpr double kAreaTolerance = 1e-9;
/// ψ/Δφ within this of an integer is that integer: rounding of π·k, not a pitch off the grid.
constexpr double kOnGrid = 1e-9;
constexpr double kMmPerUm = 1e-3;
/// ln 1e-6: chips below 10⁻⁶ of the rigid chip count as pushed back (as MillingModel).
const double kLogFloor = std::log(1e-6);

constexpr unsigned kContact = 1u << 6;
constexpr unsigned kRemoved = 1u << 7;
constexpr unsigned kPloughing = 1u << 8;
constexpr unsigned kInJump = 1u << 9;
constexpr unsigned kPushedBack = 1u << 10;

/// Slots gathered together by compute_areas(): eight doubles side by side per revolution.
constexpr std::size_t kAreaTile = 8;

int positive_mod(int a, int m) {
  const int r = a % m;
  return r < 0 ? r + m : r;
}

/// What one pass of a flute through a slot did.
struct PassResult {
  double h_rigid_um = 0.0;  ///< rigid chip, ≥ 0
  double h_um = 0.0;        ///< cut chip after deflection
  double log_h_um = 0.0;    ///< ln h (valid when h > 0 and the deflection solve gave it)
  double deficit_um = 0.0;  ///< how far the surface it leaves lies behind its rigid path
  double d_deficit = 0.0;   ///< ∂deficit/∂(deficit of the pass `argmin` back)
  int argmin = 0;           ///< nearest previous pass (1..P); 0: none
  unsigned code = 0;        ///< the discrete choices, for comparing patterns
};

/// One stored pass of a slot's cycle.
struct PassRecord {
  double h_rigid_um = 0.0;
  double h_um = 0.0;
  double log_h_um = 0.0;
  unsigned char contact = 0;
  unsigned char removed = 0;
};

/// Dense solve of A·x = b (n ≤ kMaxNewtonDim) by Gaussian elimination with partial pivoting, in
/// place (A row-major n×n, b becomes x). Returns false for a singular matrix.
bool solve_dense(double* a, double* b, int n) {
  for (int col = 0; col < n; ++col) {
    int pivot = col;
    for (int r = col + 1; r < n; ++r) {
      if (std::fabs(a[r * n + col]) > std::fabs(a[pivot * n + col])) {
        pivot = r;
      }
    }
    if (std::fabs(a[pivot * n + col]) < 1e-300) {
      return false;
    }
    if (pivot != col) {
      for (int k = 0; k < n; ++k) {
        std::swap(a[pivot * n + k], a[col * n + k]);
      }
      std::swap(b[pivot], b[col]);
    }
    const double inv = 1.0 / a[col * n + col];
    for (int r = col + 1; r < n; ++r) {
      const double f = a[r * n + col] * inv;
      if (f == 0.0) {
        continue;
      }
      for (int k = col; k < n; ++k) {
        a[r * n + k] -= f * a[col * n + k];
      }
      b[r] -= f * b[col];
    }
  }
  for (int r = n - 1; r >= 0; --r) {
    double s = b[r];
    for (int k = r + 1; k < n; ++k) {
      s -= a[r * n + k] * b[k];
    }
    b[r] = s / a[r * n + r];
  }
  return true;
}

/// evaluate_force_basis()'s columns for a law and its regimes.
std::span<const char* const> linear_coefficient_names(ForceLawKind law, bool min_chip,
                                                      bool area_law) {
  static constexpr const char* kLinearEdge[] = {"k_tc_N_per_mm2", "k_nc_N_per_mm2",
                                                "k_ac_N_per_mm2", "k_te_N_per_mm",
                                                "k_ne_N_per_mm",  "k_ae_N_per_mm"};
  static constexpr const char* kLinearArea[] = {"k_tc_N_per_mm2", "k_nc_N_per_mm2",
                                                "k_ac_N_per_mm2", "k_tp_N_per_mm3",
                                                "k_np_N_per_mm3", "k_ap_N_per_mm3"};
  static constexpr const char* kPower[] = {"k_tc_Nmm", "k_nc_Nmm", "k_ac_Nmm",
                                           "k_tp_Nmm", "k_np_Nmm", "k_ap_Nmm"};
  static constexpr const char* kKronenberg[] = {"k_s0_N_per_mm2"};
  switch (law) {
    case ForceLawKind::kLinearEdge:
      return area_law ? std::span<const char* const>(kLinearArea) : kLinearEdge;
    case ForceLawKind::kPowerLaw:
      // The ploughing regime's coefficients only when [000]'s minimum chip thickness is on.
      return std::span<const char* const>(kPower).first(min_chip ? 6 : 3);
    case ForceLawKind::kKronenberg:
      break;
  }
  return kKronenberg;
}

}  // namespace

void at_actual_speed(const ModelConfig& commanded, double actual_rpm, ModelConfig& out) {
  if (!(actual_rpm > 0.0) || !std::isfinite(actual_rpm)) {
    throw std::invalid_argument("at_actual_speed: actual_rpm must be > 0, got " +
                                std::to_string(actual_rpm));
  }
  out = commanded;
  out.process.spindle_rpm = actual_rpm;
  out.process.feed_per_tooth_um =
      commanded.process.feed_per_tooth_um * commanded.process.spindle_rpm / actual_rpm;
}

ModelConfig at_actual_speed(const ModelConfig& commanded, double actual_rpm) {
  ModelConfig out;
  at_actual_speed(commanded, actual_rpm, out);
  return out;
}

std::span<const double> SteadyState::revolution(int m, int axis) const {
  if (m < 0 || m >= cycle_revolutions || axis < 0 || axis > 2) {
    throw std::out_of_range("SteadyState::revolution: revolution " + std::to_string(m) + " of " +
                            std::to_string(cycle_revolutions) + ", axis " + std::to_string(axis));
  }
  const std::vector<double>& v = axis == 0 ? cycle.fx_N : axis == 1 ? cycle.fy_N : cycle.fz_N;
  return std::span<const double>(v).subspan(static_cast<std::size_t>(m * steps_per_rev),
                                            static_cast<std::size_t>(steps_per_rev));
}

struct SteadyStateWorkspace::Impl {
  // ---- the configuration, derived once per evaluation
  int flutes = 0, steps = 0, discs = 1, passes = 1;
  double d_phi_rad = 0.0, dz_mm = 0.0, h_min_um = 0.0, disc_stiffness_N_per_um = 0.0;
  double normal_jump_N = 0.0;   // F_n(h_min) − F_n(h_min−) of one disc: the regime switch
  double below_h_min_um = 0.0;  // h_min·(1 − 1e-12)
  double log_h_min_um = 0.0, log_below_h_min_um = 0.0;         // ln h_min, ln(h_min·(1 − 1e-12))
  double normal_at_h_min_N = 0.0, normal_below_h_min_N = 0.0;  // F_n there (no area: see below)
  bool deflect = false, accumulate = false, area_law = false, memory = false;
  bool rigid_axis_discs = false;  // helix on and RunoutHelix::kRigidAxis
  bool dynamometer = false;
  Effects::Dynamometer dyn;
  double spindle_hz = 0.0;
  ForceLaw law;
  Material material_coefficients;  // names unused; kept for the basis
  ForceLawKind law_kind = ForceLawKind::kPowerLaw;
  bool min_chip = false;

  ChipGeometry geometry;
  // What the chip tables were made for (with the pitch and the discs' angles).
  struct GeometryKey {
    PathGeometry path;
    bool trochoidal = false;
    int passes = 0, steps = 0;
    double from_rad = 0.0, to_rad = 0.0;  // the trochoid's window
    bool operator==(const GeometryKey&) const = default;
  };
  bool geometry_valid = false;
  GeometryKey geometry_key;
  std::vector<double> key_pitch;
  std::vector<double> key_disc_angles;

  std::vector<double> pitch_rad;           // ψ_j, exact
  std::vector<double> disc_angles;         // per disc, added to γ (rigid tool axis), or empty
  std::vector<double> wear_t_N, wear_n_N;  // per flute
  std::vector<double> radius_mm;           // per (disc, flute): cutting radius
  std::vector<int> land_steps;             // ⌊ψ_j/Δφ⌋
  std::vector<double> land_frac;           // (ψ_j/Δφ) mod 1
  // Without pass memory each flute has its own immersion grid, shifted by land_frac so that its
  // passes land on the output grid; with memory the flutes share the slots and flute j's force
  // is interpolated onto the grid (weight land_frac).
  std::vector<double> immersion_frac, output_frac;  // per flute
  std::vector<int> table_offset;                    // per (disc, flute): table index − b
  std::vector<double> table_frac;
  std::vector<double> cos_grid, sin_grid;  // cos, sin of 2πb/S
  int grid_steps = 0;
  std::vector<double> cos_theta, sin_theta;  // per (disc, flute, slot)
  std::vector<unsigned char> engaged;        // per (disc, flute, slot)
  // What cos_theta, sin_theta and engaged were filled for: a fit changes runout and coefficients
  // between evaluations, not the immersion grid.
  struct ImmersionKey {
    int flutes = 0, steps = 0, discs = 0;
    double beta_rad = 0.0, engage_from_rad = 0.0, engage_to_rad = 0.0;
    bool operator==(const ImmersionKey&) const = default;
  };
  bool immersion_valid = false;
  ImmersionKey immersion_key;
  std::vector<double> key_immersion_frac;  // with immersion_key
  [[nodiscard]] std::size_t flute_slot(int disc, int flute, int b) const {
    return static_cast<std::size_t>((disc * flutes + flute) * steps + b);
  }

  // ---- slot solutions
  std::vector<int> period, phase;  // per (disc, slot): p_s and r_s
  std::vector<int> record_offset;  // per (disc, slot) into records
  std::vector<PassRecord> records;

  // ---- slot scratch
  std::vector<double> g;                   // N·P geometric chips of the slot, oldest pass first
  std::vector<double> no_deficits;         // P zeros: the fresh cut's passes
  std::vector<double> hist;                // deficits of every pass so far (first P: the fresh cut)
  std::vector<std::uint64_t> no_cut;       // [len]: bit t − 1 set where hist[len − t] is kNoCut
  std::vector<unsigned> codes;             // per pass
  std::vector<double> guess;               // per flute: last cut chip (deflection solve's start)
  std::vector<PassRecord> trajectory;      // per pass of the slot's iteration
  std::vector<PassRecord> one_revolution;  // per flute, memoryless slots
  std::vector<double> nt_vals, nt_grads, nt_x, nt_y, nt_f, nt_j, nt_gy, nt_h;
  std::vector<PassRecord> nt_records;  // the passes of Newton's last run

  // ---- ploughed area ([001] eqs 14-17), per (disc, slot, flute, revolution of area_cycle)
  std::vector<double> area, walk_h, walk_area;    // walk_*: one flute's passes in time order
  std::vector<double> area_mean, area_mean_prev;  // per (disc, slot, flute): mean over the cycle
  int area_cycle = 1;
  bool area_coupled = false;  // area used inside the slot solve (with deflection)

  // ---- forces per flute and slot (3 axes), mean and cycle
  std::array<std::vector<double>, 3> flute_mean, flute_cycle;
  std::array<std::vector<double>, 3> basis_flute;  // (columns + 1)·N·S

  SteadyState result;
  ForceBasis basis;
  PeriodicResponse mean_response;
  std::vector<PeriodicResponse> cycle_response;  // index L

  void configure(const ModelConfig& c, double rpm, int steps_per_rev);
  void size_storage();
  /// cos θ, sin θ and engagement of flute `flute`'s slots on disc `disc`, its slot 0 `back_rad`
  /// behind the spindle angle.
  void fill_immersion(int disc, int flute, double back_rad, double engage_from_rad,
                      double engage_to_rad);
  [[nodiscard]] int first_flute(int b) const;
  void fill_geometric_chips(int disc, int b);
  [[nodiscard]] double area_input(int slot, int flute) const;
  struct Deflection {
    double h_um = 0.0, log_h_um = 0.0, dh_dhr = 0.0;
    unsigned code = 0;
  };
  /// @param guess_log_um ln of a chip to start from (+∞: none)
  [[nodiscard]] Deflection solve_deflection(double h_rigid_um, double wear_normal_N,
                                            double area_mm2, double guess_log_um) const;
  /// @param deficits the last P passes' deficits, the oldest first (pass n back at P − n)
  PassResult run_pass(int flute, bool engaged_slot, double area_mm2, double guess_log_um,
                      const double* deficits) const;
  void solve_slots();
  void solve_slot(int disc, int b);
  bool newton(int slot, int first, int p, int r, std::size_t len);
  void store_cycle(int slot, const PassRecord* passes_in_order, int first, int p);
  void compute_cycle_length();
  void compute_areas();
  void accumulate_forces(bool with_cycle);
  void accumulate_basis();
  /// accumulate_basis() for the linear edge law without the ploughed area (columns K_tc, K_nc,
  /// K_ac, K_te, K_ne, K_ae, then the offset at `offset_column`), into zeroed basis_flute.
  void accumulate_linear_edge_basis(std::size_t offset_column, bool plough_law);
  void assemble(std::span<const double> per_flute, int revolutions, int m,
                std::span<double> out) const;
  void apply_dynamometer(std::span<double> waveform, int axis, int revolutions);
  void evaluate(const ModelConfig& c, double rpm, int steps_per_rev, SteadyStateOutput output,
                bool forces = true);
};

// ---------------------------------------------------------------------------------------------
// Configuration

void SteadyStateWorkspace::Impl::configure(const ModelConfig& c, double rpm, int steps_per_rev) {
  validate(c);
  if (!(rpm > 0.0) || !std::isfinite(rpm)) {
    throw std::invalid_argument("steady state: spindle_rpm must be > 0, got " +
                                std::to_string(rpm));
  }
  if (steps_per_rev < 36 || steps_per_rev > 36000) {
    throw std::invalid_argument("steady state: steps_per_rev must be in [36, 36000], got " +
                                std::to_string(steps_per_rev));
  }
  const Effects& e = c.effects;
  flutes = c.tool.flutes;
  steps = steps_per_rev;
  discs = e.helix_lag.enabled ? e.helix_lag.discs : 1;
  rigid_axis_discs = e.helix_lag.enabled && e.runout.helix == RunoutHelix::kRigidAxis;
  passes = passes_to_look_back(c);
  d_phi_rad = 2.0 * kPi / steps;
  dz_mm = c.process.axial_depth_mm / discs;
  spindle_hz = rpm / 60.0;
  deflect = e.deflection.enabled;
  accumulate = e.accumulation.enabled;
  min_chip = e.min_chip.enabled;
  law_kind = c.material.law;
  area_law = law_kind == ForceLawKind::kLinearEdge && c.material.linear_edge.ploughing_area;
  memory = deflect || accumulate;
  dynamometer = e.dynamometer.enabled;
  dyn = e.dynamometer;
  h_min_um = min_chip ? e.min_chip.h_min_um : 0.0;
  law = ForceLaw(c.material, c.process.axial_depth_mm, h_min_um, min_chip);
  material_coefficients.law = c.material.law;
  material_coefficients.power_law = c.material.power_law;
  material_coefficients.linear_edge = c.material.linear_edge;
  material_coefficients.kronenberg = c.material.kronenberg;
  disc_stiffness_N_per_um = e.deflection.stiffness_N_per_um / discs;
  below_h_min_um = normal_at_h_min_N = normal_below_h_min_N = normal_jump_N = 0.0;
  log_h_min_um = log_below_h_min_um = 0.0;
  if (h_min_um > 0.0) {
    // The ploughed-area law is continuous at h_min: its jump is 0 whatever the area, so these
    // are F_n at h_min± for every law whose balance meets the jump.
    below_h_min_um = h_min_um * (1.0 - 1e-12);
    normal_at_h_min_N = law.normal_N(h_min_um, dz_mm);
    normal_below_h_min_N = law.normal_N(below_h_min_um, dz_mm);
    normal_jump_N = normal_at_h_min_N - normal_below_h_min_N;
    log_h_min_um = std::log(h_min_um);
    log_below_h_min_um = std::log(below_h_min_um);
  }
  if (std::fabs(normal_jump_N) <= 1e-9 * std::fabs(normal_at_h_min_N)) {
    normal_jump_N = 0.0;  // continuous at h_min (up to the 1e-12 step): one branch
  }

  // The kept chip tables and immersion grid count again only once this set-up is whole: an
  // exception on the way (a failed allocation) leaves them to be remade.
  const bool geometry_was_valid = std::exchange(geometry_valid, false);
  const bool immersion_was_valid = std::exchange(immersion_valid, false);
  size_storage();

  // Pitch: exact. ψ_j/Δφ within rounding of an integer is that integer.
  flute_pitch_angles_rad(c.tool, pitch_rad);
  for (int j = 0; j < flutes; ++j) {
    double s = pitch_rad[static_cast<std::size_t>(j)] / d_phi_rad;
    if (std::fabs(s - std::round(s)) < kOnGrid) {
      s = std::round(s);
    }
    const double whole = std::floor(s);
    land_steps[static_cast<std::size_t>(j)] = static_cast<int>(whole);
    land_frac[static_cast<std::size_t>(j)] = s - whole;
    immersion_frac[static_cast<std::size_t>(j)] = memory ? 0.0 : s - whole;
    output_frac[static_cast<std::size_t>(j)] = memory ? s - whole : 0.0;
  }

  const double radius_um = tool_radius_um(c);
  PathGeometry path;
  path.radius_um = radius_um;
  path.feed_per_rad_um = c.process.feed_per_tooth_um * flutes / (2.0 * kPi);
  path.offset_um = e.runout.enabled ? e.runout.offset_um : 0.0;
  path.offset_angle_rad = e.runout.enabled ? e.runout.angle_rad : 0.0;

  // Engaged immersion: [000] eq 28 for side milling, [0, π] for a slot.
  const EngagedArc arc = engaged_arc(c);
  const double engage_from = arc.from_rad;
  const double engage_to = arc.to_rad;
  const double beta = helix_lag_total_rad(c);
  runout_disc_angles_rad(c, disc_angles);
  const double margin = 4.0 * d_phi_rad;
  const double from = engage_from - margin;
  const double to = engage_to + beta + margin;
  const GeometryKey g_key{path, e.trochoidal.enabled, passes, steps, from, to};
  const bool same_geometry = geometry_was_valid && g_key == geometry_key &&
                             key_pitch == pitch_rad && key_disc_angles == disc_angles;
  if (!same_geometry) {
    geometry.configure(path, pitch_rad, passes, steps, e.trochoidal.enabled, from, to, disc_angles);
    geometry_key = g_key;
    key_pitch = pitch_rad;  // same size after the first time: no allocation
    key_disc_angles = disc_angles;
  }
  geometry_valid = true;

  const ImmersionKey i_key{flutes, steps, discs, beta, engage_from, engage_to};
  const bool same_immersion =
      immersion_was_valid && i_key == immersion_key && key_immersion_frac == immersion_frac;
  for (int i = 0; i < discs; ++i) {
    const double lag = (i + 0.5) * beta / discs;
    const double lag_steps = lag / d_phi_rad;
    for (int j = 0; j < flutes; ++j) {
      const auto uj = static_cast<std::size_t>(j);
      // Flute j's slot b is immersion θ = 2π(b − e_j)/S − lag_i (e_j = immersion_frac); the
      // flute reaches it at spindle angle 2π(b + ⌊ψ_j/Δφ⌋ + w_j − e_j)/S and reads the chip
      // tables there, less the lag.
      const double shift = land_frac[uj] - immersion_frac[uj] - lag_steps;
      const double whole = std::floor(shift);
      const auto ij = static_cast<std::size_t>(i * flutes + j);
      table_offset[ij] = land_steps[uj] + static_cast<int>(whole);
      table_frac[ij] = shift - whole;
      if (!same_immersion) {
        fill_immersion(i, j, lag + immersion_frac[uj] * d_phi_rad, engage_from, engage_to);
      }
    }
  }
  if (!same_immersion) {
    immersion_key = i_key;
    key_immersion_frac = immersion_frac;  // same size after the first time: no allocation
  }
  immersion_valid = true;

  for (int j = 0; j < flutes; ++j) {
    const auto uj = static_cast<std::size_t>(j);
    wear_t_N[uj] = 0.0;
    wear_n_N[uj] = 0.0;
    if (e.flank_wear.enabled) {
      const auto& w = e.flank_wear.wear_um;
      const double vb_mm = 1e-3 * (w.size() == 1 ? w[0] : w[uj]);
      wear_t_N[uj] = e.flank_wear.k_wt_N_per_mm2 * vb_mm * dz_mm;
      wear_n_N[uj] = e.flank_wear.k_wn_N_per_mm2 * vb_mm * dz_mm;
    }
    for (int i = 0; i < discs; ++i) {
      radius_mm[static_cast<std::size_t>(i * flutes + j)] =
          1e-3 * geometry.flutes_at(i)[uj].radius_um;
    }
  }
}

void SteadyStateWorkspace::Impl::fill_immersion(int disc, int flute, double back_rad,
                                                double engage_from_rad, double engage_to_rad) {
  const double cl = std::cos(back_rad);
  const double sl = std::sin(back_rad);
  const std::size_t first = flute_slot(disc, flute, 0);
  double* cos_out = &cos_theta[first];
  double* sin_out = &sin_theta[first];
  unsigned char* engaged_out = &engaged[first];
  for (int b = 0; b < steps; ++b) {
    const auto ub = static_cast<std::size_t>(b);
    cos_out[ub] = cos_grid[ub] * cl + sin_grid[ub] * sl;
    sin_out[ub] = sin_grid[ub] * cl - cos_grid[ub] * sl;
    double theta = b * d_phi_rad - back_rad;  // back ∈ [0, 2π): one wrap at most
    if (theta < 0.0) {
      theta += 2.0 * kPi;
    }
    engaged_out[ub] = theta >= engage_from_rad && theta <= engage_to_rad ? 1 : 0;
  }
}

void SteadyStateWorkspace::Impl::size_storage() {
  const auto n = static_cast<std::size_t>(flutes);
  const auto s = static_cast<std::size_t>(steps);
  const auto d = static_cast<std::size_t>(discs);
  const auto p = static_cast<std::size_t>(passes);
  pitch_rad.resize(n);
  wear_t_N.resize(n);
  wear_n_N.resize(n);
  radius_mm.resize(d * n);
  disc_angles.reserve(d);
  key_disc_angles.reserve(d);
  // One chip table per disc when runout meets the helix on a rigid axis: reserved whether or not
  // runout is on now, so that switching it on allocates nothing.
  geometry.reserve(flutes, passes, steps, rigid_axis_discs ? discs : 1);
  land_steps.resize(n);
  land_frac.resize(n);
  table_offset.resize(d * n);
  table_frac.resize(d * n);
  cos_theta.resize(d * n * s);
  sin_theta.resize(d * n * s);
  engaged.resize(d * n * s);
  immersion_frac.resize(n);
  output_frac.resize(n);
  if (grid_steps != steps) {
    cos_grid.resize(s);
    sin_grid.resize(s);
    for (int b = 0; b < steps; ++b) {
      cos_grid[static_cast<std::size_t>(b)] = std::cos(b * 2.0 * kPi / steps);
      sin_grid[static_cast<std::size_t>(b)] = std::sin(b * 2.0 * kPi / steps);
    }
    grid_steps = steps;
  }
  period.resize(d * s);
  phase.resize(d * s);
  record_offset.resize(d * s);
  if (records.capacity() < d * s * n * (memory ? 4 : 1)) {
    records.reserve(d * s * n * (memory ? 4 : 1));
  }
  g.resize(n * p);
  no_deficits.assign(p, 0.0);
  one_revolution.resize(n);
  guess.resize(n);
  if (memory) {
    hist.resize(p + static_cast<std::size_t>(kMaxSlotRevolutions + 1) * n);
    no_cut.resize(hist.size() + 1);
    trajectory.resize(static_cast<std::size_t>(kMaxSlotRevolutions + 1) * n);
    codes.resize(static_cast<std::size_t>(kMaxSlotRevolutions + 1) * n);
    const auto m = static_cast<std::size_t>(kMaxNewtonDim);
    nt_vals.resize(p + m);
    nt_grads.resize((p + m) * m);
    nt_x.resize(m);
    nt_y.resize(m);
    nt_f.resize(m);
    nt_j.resize(m * m);
    nt_gy.resize(m * m);
    nt_h.resize(m);
    nt_records.resize(m);
  }
  const std::size_t cycle_cap = memory ? static_cast<std::size_t>(kMaxCycleRevolutions) : 1;
  if (area_law) {
    area.reserve(d * s * n * cycle_cap);
    area_mean.resize(d * s * n);
    area_mean_prev.resize(d * s * n);
    walk_h.reserve(s * cycle_cap);
    walk_area.reserve(s * cycle_cap);
  }
  for (int a = 0; a < 3; ++a) {
    flute_mean[static_cast<std::size_t>(a)].resize(n * s);
    flute_cycle[static_cast<std::size_t>(a)].reserve(n * s * cycle_cap);
    basis_flute[static_cast<std::size_t>(a)].resize(n * s * (kMaxBasisColumns + 1));
  }
  for (auto* w : {&result.mean, &result.cycle}) {
    w->fx_N.reserve(s * cycle_cap);
    w->fy_N.reserve(s * cycle_cap);
    w->fz_N.reserve(s * cycle_cap);
  }
  result.mean.fx_N.resize(s);
  result.mean.fy_N.resize(s);
  result.mean.fz_N.resize(s);
  for (auto& w : basis.unit) {
    w.fx_N.resize(s);
    w.fy_N.resize(s);
    w.fz_N.resize(s);
  }
  basis.offset.fx_N.resize(s);
  basis.offset.fy_N.resize(s);
  basis.offset.fz_N.resize(s);
  if (mean_response.samples() != steps) {
    mean_response = PeriodicResponse(steps);
  }
  if (cycle_response.size() < static_cast<std::size_t>(kMaxCycleRevolutions + 1)) {
    cycle_response.resize(static_cast<std::size_t>(kMaxCycleRevolutions + 1));
  }
}

int SteadyStateWorkspace::Impl::first_flute(int b) const {
  // Flute j passes slot b at spindle step b + ψ_j/Δφ; those at or past a full turn come first
  // in the revolution (flute 0, ψ_0 = 0, never does).
  for (int j = 1; j < flutes; ++j) {
    if (b + land_steps[static_cast<std::size_t>(j)] + land_frac[static_cast<std::size_t>(j)] >=
        steps) {
      return j;
    }
  }
  return 0;
}

void SteadyStateWorkspace::Impl::fill_geometric_chips(int disc, int b) {
  for (int j = 0; j < flutes; ++j) {
    const auto ij = static_cast<std::size_t>(disc * flutes + j);
    const int k0 = positive_mod(b + table_offset[ij], steps);
    const int k1 = k0 + 1 == steps ? 0 : k0 + 1;
    const double w = table_frac[ij];
    for (int n = 1; n <= passes; ++n) {
      const double* row = geometry.row(j, n, disc);
      g[static_cast<std::size_t>(j * passes + passes - n)] = row[k0] + w * (row[k1] - row[k0]);
    }
  }
}

double SteadyStateWorkspace::Impl::area_input(int slot, int flute) const {
  // With deflection the ploughed area enters the balance through F_n; each pass uses its slot's
  // mean area over the cycle of the previous solution (the force itself uses its own).
  return area_coupled ? area_mean_prev[static_cast<std::size_t>(slot * flutes + flute)] : 0.0;
}

// ---------------------------------------------------------------------------------------------
// Deflection ([000] eqs 21-23 with the flank-wear normal force): the cut chip h of
//   G(h) = h + (F_n(h) + F_w)/k − h_r = 0,   k the disc's share of the stiffness.
// G increases with h on each regime's branch, but F_n may jump at h_min — upwards or downwards
// ([000] Table 2: K_np·h_min^a_np > K_nc·h_min^a_nc, a fall). With a fall both branches can
// hold a root; the tool stops at the first balance it meets as it goes in, so the chip is the
// smallest root, whatever any starting guess says (MillingModel takes whichever root its Newton
// start, the neighbouring step, leads to). A rise can leave no root: the chip then stays at h_min.
// Halley's method runs in u = ln h, where F_n ∝ h^a (a < 1) is well conditioned, inside the
// branch's bracket (bisection when it would leave it), to |Δu| < 1e-7 (cubic: nothing left above
// rounding). G' and G'' come with F_n at no further cost (d²F_n/du² = a²·F_n for a power law):
// from the neighbouring pass's chip it needs two to three steps where Newton took three to four,
// each with two exponentials.

SteadyStateWorkspace::Impl::Deflection SteadyStateWorkspace::Impl::solve_deflection(
    double h_rigid, double wear_n, double area_mm2, double guess_log_um) const {
  Deflection d;
  const double k = disc_stiffness_N_per_um;
  const double inv_k = 1.0 / k;
  // G at x given F_n(x) (at h_min± known from configure()).
  auto excess_given = [&](double x, double normal) {
    return x + (normal + wear_n) * inv_k - h_rigid;
  };
  auto excess = [&](double x) { return excess_given(x, law.normal_N(x, dz_mm, area_mm2)); };
  if (wear_n >= k * h_rigid) {
    d.code = kPushedBack;  // the rubbing force alone pushes the tool back beyond this chip
    return d;
  }
  const double floor_um = 1e-6 * h_rigid;
  double lo = floor_um;
  double hi = h_rigid;
  if (normal_jump_N != 0.0 && h_min_um > floor_um && h_min_um < h_rigid) {
    if (excess_given(below_h_min_um, normal_below_h_min_N) >= 0.0) {
      hi = below_h_min_um;  // a root on the ploughing branch: the smallest
    } else if (normal_jump_N < 0.0 || excess_given(h_min_um, normal_at_h_min_N) <= 0.0) {
      lo = h_min_um;  // none below h_min: the cutting branch (certain after a fall)
    } else {
      d.h_um = h_min_um;  // the balance falls into F_n's rise at h_min
      d.log_h_um = log_h_min_um;
      d.code = kInJump;
      return d;
    }
  }
  // A normal force affine in h on the bracket's branch (the linear-edge law) makes G a line,
  // G(h) = (1 + a/k)·h + (b + F_w)/k − h_r, solved at once. Over the whole chip range (no jump
  // at h_min), where it does not rise through 0 inside: G ≥ 0 at the floor pushes the tool back
  // (as below, whichever way G goes: the first balance met going in); G < 0 throughout leaves
  // the rigid chip (a fit's trial coefficients: a normal force falling with the chip, or pulling
  // the tool in). The iteration below had bisected such lines for 100 exponentials, to the
  // floor or the rigid chip depending on its start: most of a linear-edge window fit's time on
  // a real cut (PHM 2010, whose fits try negative K_nc).
  const ForceLaw::AffineNormal affine = law.affine_normal(dz_mm, area_mm2, hi != h_rigid);
  if (affine.valid) {
    const double rise = 1.0 + affine.slope_N_per_um * inv_k;
    const double offset = (affine.intercept_N + wear_n) * inv_k - h_rigid;
    const double h = -offset / rise;
    // A line over every chip needs no ln h: the linear-edge force does not take it, and no
    // iteration will start from it (NaN: none, and nothing can use it unawares).
    const bool everywhere = law.affine_normal(dz_mm, area_mm2, true).valid;
    // (A root below h_min where [002] eq 17's power law holds is not this line's.)
    const bool line_holds = everywhere || !law.ploughing(h);
    if (rise > 0.0 && h > lo && h < hi && line_holds) {
      d.h_um = h;
      d.log_h_um = everywhere ? std::numeric_limits<double>::quiet_NaN() : std::log(h);
      d.dh_dhr = std::clamp(1.0 / rise, 0.0, 1.0);
      return d;
    }
    const bool whole_range = lo == floor_um && hi == h_rigid;
    if (whole_range && everywhere) {
      if (rise * floor_um + offset >= 0.0) {
        d.code = kPushedBack;
        return d;
      }
      if (rise <= 0.0 || h >= h_rigid) {
        d.h_um = h_rigid;
        d.log_h_um = std::numeric_limits<double>::quiet_NaN();
        d.dh_dhr = 1.0;
        return d;
      }
    }
  }
  // G is convex in u (each term is a constant or K·e^{a·u}, a > 0). Halley's step
  // G·G'/(G'² − G·G''/2) is Newton's G/G' shortened below the root and lengthened above it;
  // far above (G·G'' ≥ G'²) it is Newton's. Clamp to the bracket's top (where G ≥ 0) when a step
  // from below overshoots it, bisect when one from above leaves the bracket, and stop when the
  // step is below 1e-7 from either side (what is left is then ~1e-21).
  const double log_rigid = std::log(h_rigid);
  const double floor_log = log_rigid + kLogFloor;
  bool floor_checked = lo != floor_um;
  double ulo = lo == floor_um ? floor_log : log_h_min_um;
  double uhi = hi == h_rigid ? log_rigid : log_below_h_min_um;
  double u = guess_log_um > ulo && guess_log_um < uhi ? guess_log_um : uhi;
  // The last step s (|s| < 1e-7) from u, where h = e^u: e^{u − s} = h·(1 − s + s²/2) within
  // s³/6 < 2e-22, no exponential needed.
  auto converged = [&](double u_at, double h, double s, const ForceLaw::NormalSlope& fs) {
    d.h_um = h * (1.0 - s + 0.5 * s * s);
    d.log_h_um = u_at - s;
    // 1/(1 + F_n'(h)/k), F_n' at the last step; in [0, 1] for a law whose force grows with the
    // chip, held there for one that falls (a fit's trial coefficients: bisected, above).
    d.dh_dhr = std::clamp(1.0 / (1.0 + fs.d_du_N / h * inv_k), 0.0, 1.0);
    return d;
  };
  for (int it = 0; it < 100; ++it) {
    const double hu = std::exp(u);
    const auto fs = law.normal_with_slope(hu, u, dz_mm, area_mm2);
    const double gap = hu + (fs.force_N + wear_n) * inv_k - h_rigid;
    const double dg_du = hu + fs.d_du_N * inv_k;
    const double d2g_du2 = hu + fs.d2_du2_N * inv_k;
    const double dg_du_2 = dg_du * dg_du;
    const double halley = dg_du_2 - 0.5 * gap * d2g_du2;
    const double step = halley > 0.5 * dg_du_2 ? gap * dg_du / halley : gap / dg_du;  // or Newton
    double next = u - step;
    if (gap < 0.0) {
      ulo = u;
      if (next >= uhi) {
        next = uhi;
      } else if (std::fabs(step) < 1e-7) {
        return converged(u, hu, step, fs);
      }
    } else if (next <= ulo) {
      if (!floor_checked && ulo == floor_log) {
        floor_checked = true;
        if (excess(floor_um) >= 0.0) {
          d.code = kPushedBack;  // pushed back before it cuts anything worth counting
          return d;
        }
      }
      next = 0.5 * (ulo + u);
    } else if (std::fabs(step) < 1e-7) {
      return converged(u, hu, step, fs);
    }
    if (gap >= 0.0) {
      uhi = u;
    }
    // A law whose normal force falls with the chip (coefficients a fit tries on its way: G is
    // then not convex, G' may be negative) sends the step out of the bracket, and it ran off to
    // u = −1e293 (100 underflowing exponentials an element): bisect instead.
    if (!(next >= ulo && next <= uhi)) {
      next = 0.5 * (ulo + uhi);
    }
    u = next;
  }
  d.h_um = std::exp(u);
  d.log_h_um = u;
  return d;
}

// ---------------------------------------------------------------------------------------------
// One pass (the physics of MillingModel::march_step for one element)

PassResult SteadyStateWorkspace::Impl::run_pass(int flute, bool engaged_slot, double area_mm2,
                                                double guess_log_um, const double* deficits) const {
  PassResult r;
  if (!engaged_slot) {
    return r;  // outside the workpiece: its rigid path is the surface (deficit 0)
  }
  // 1. rigid chip: the nearest previous pass that removed material, plus its deficit.
  const double* gj = &g[static_cast<std::size_t>(flute * passes)];
  const auto [h_rigid_found, arg_found] = nearest_removal(gj, deficits, passes);
  double h_rigid = h_rigid_found;
  int arg = arg_found;
  if (h_rigid == kNoCut) {  // no pass in the window removed material: take the oldest
    h_rigid = gj[0];
    arg = 0;
  }
  if (h_rigid <= 0.0) {
    r.code = static_cast<unsigned>(arg);
    return r;  // not in contact: deficit 0
  }
  r.h_rigid_um = h_rigid;
  r.argmin = arg;
  unsigned code = static_cast<unsigned>(arg) | kContact;

  // 2. deflection ([000] eqs 21-23): h + (F_n(h) + F_w)/k = h_r for the cut chip h ∈ [0, h_r].
  double h = h_rigid;
  double log_h = 0.0;
  double dh_dhr = 1.0;
  if (deflect) {
    const Deflection d = solve_deflection(h_rigid, wear_n_N[static_cast<std::size_t>(flute)],
                                          area_mm2, guess_log_um);
    h = d.h_um;
    log_h = d.log_h_um;
    dh_dhr = d.dh_dhr;
    code |= d.code;
  }
  r.h_um = h;
  r.log_h_um = log_h;

  // 3. regime and accumulation ([000] eq 5, [002] eqs 11-12)
  const bool ploughing = law.ploughing(h);
  const bool removed = !(accumulate && ploughing);
  if (ploughing) {
    code |= kPloughing;
  }
  if (removed) {
    code |= kRemoved;
    r.deficit_um = h_rigid - h;
    r.d_deficit = arg > 0 && deflect ? 1.0 - dh_dhr : 0.0;
  } else {
    r.deficit_um = kNoCut;
  }
  r.code = code;
  return r;
}

// ---------------------------------------------------------------------------------------------
// Slots

void SteadyStateWorkspace::Impl::solve_slots() {
  records.clear();
  for (int i = 0; i < discs; ++i) {
    for (int b = 0; b < steps; ++b) {
      solve_slot(i, b);
    }
  }
}

namespace {

/// `with_log`: ln h wanted (the power law's element force uses it; the deflection solve gives
/// it for free).
PassRecord to_record(const PassResult& pr, bool deflect, bool with_log) {
  PassRecord rec;
  rec.h_rigid_um = pr.h_rigid_um;
  rec.h_um = pr.h_um;
  rec.log_h_um =
      pr.h_um > 0.0 && (deflect || with_log) ? (deflect ? pr.log_h_um : std::log(pr.h_um)) : 0.0;
  rec.contact = pr.h_rigid_um > 0.0 ? 1 : 0;
  rec.removed = (pr.code & kRemoved) != 0 ? 1 : 0;
  return rec;
}

}  // namespace

void SteadyStateWorkspace::Impl::store_cycle(int slot, const PassRecord* passes_in_order, int first,
                                             int p) {
  // Records of a slot: index c·N + j for revolution c of its cycle and flute j.
  const auto n = static_cast<std::size_t>(flutes);
  const auto us = static_cast<std::size_t>(slot);
  record_offset[us] = static_cast<int>(records.size());
  period[us] = p;
  records.resize(records.size() + static_cast<std::size_t>(p) * n);
  PassRecord* out = &records[static_cast<std::size_t>(record_offset[us])];
  for (int c = 0; c < p; ++c) {
    // Pass q = c·N + i of the slot is flute (first + i) mod N's.
    const PassRecord* in = passes_in_order + static_cast<std::ptrdiff_t>(c) * flutes;
    PassRecord* revolution = out + static_cast<std::ptrdiff_t>(c) * flutes;
    int j = first;
    for (int i = 0; i < flutes; ++i) {
      revolution[j] = in[i];
      j = j + 1 == flutes ? 0 : j + 1;
    }
  }
}

void SteadyStateWorkspace::Impl::solve_slot(int disc, int b) {
  const int slot = disc * steps + b;
  const auto uslot = static_cast<std::size_t>(slot);
  const auto n = static_cast<std::size_t>(flutes);
  phase[uslot] = 0;
  bool any = false;
  for (int j = 0; j < flutes; ++j) {
    any = any || engaged[flute_slot(disc, j, b)] != 0;
  }
  if (!any) {  // never in the workpiece: no contact, deficits stay 0
    record_offset[uslot] = static_cast<int>(records.size());
    period[uslot] = 1;
    records.resize(records.size() + n);
    std::fill(records.end() - static_cast<std::ptrdiff_t>(n), records.end(), PassRecord{});
    return;
  }
  fill_geometric_chips(disc, b);
  const int first = first_flute(b);
  if (!memory) {
    // The deficits stay 0: the fresh cut's first revolution is already the steady state.
    for (int q = 0; q < flutes; ++q) {
      const int j = (first + q) % flutes;
      one_revolution[static_cast<std::size_t>(q)] = to_record(
          run_pass(j, engaged[flute_slot(disc, j, b)] != 0, 0.0, kNoCut, no_deficits.data()),
          deflect, law_kind == ForceLawKind::kPowerLaw);
    }
    store_cycle(slot, one_revolution.data(), first, 1);
    result.stats.passes += flutes;
    return;
  }
  for (int j = 0; j < flutes; ++j) {
    guess[static_cast<std::size_t>(j)] = kNoCut;
  }
  std::fill(hist.begin(), hist.begin() + passes, 0.0);
  std::size_t len = static_cast<std::size_t>(passes);
  const auto p_len = static_cast<std::size_t>(passes);
  // Which of the last P passes removed nothing, as bits: two states whose bits differ are not the
  // same (kNoCut matches only itself), found without reading them (the last 64 where P > 64).
  const std::uint64_t window_bits =
      p_len >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << p_len) - 1;
  no_cut[len] = 0;

  auto same_state = [&](std::size_t a_end, std::size_t b_end) {
    if (no_cut[a_end] != no_cut[b_end]) {
      return false;
    }
    for (std::size_t t = 1; t <= p_len; ++t) {
      const double x = hist[a_end - t];
      const double y = hist[b_end - t];
      if (x == y) {
        continue;
      }
      if (x == kNoCut || y == kNoCut || std::fabs(x - y) > kDeficitTolerance_um) {
        return false;
      }
    }
    return true;
  };
  auto same_codes = [&](int r_a, int r_b, int revs) {
    const auto a = static_cast<std::size_t>(r_a) * n;
    const auto c = static_cast<std::size_t>(r_b) * n;
    for (std::size_t t = 0; t < static_cast<std::size_t>(revs) * n; ++t) {
      if (codes[a + t] != codes[c + t]) {
        return false;
      }
    }
    return true;
  };
  auto settle = [&](int r) {
    result.stats.longest_transient_revolutions =
        std::max(result.stats.longest_transient_revolutions, r);
  };

  int newton_wait = 0;
  for (int r = 0;; ++r) {
    // Has the state (the last P deficits) repeated? Then revolutions r − p .. r − 1 are the
    // cycle (revolution r − p is its phase 0).
    for (int p = 1; p <= std::min(r, kMaxSlotPeriodRevolutions); ++p) {
      if (same_state(len, len - static_cast<std::size_t>(p) * n)) {
        store_cycle(slot, &trajectory[static_cast<std::size_t>(r - p) * n], first, p);
        phase[uslot] = r - p;
        settle(r);
        return;
      }
    }
    // With deflection the leftovers converge only geometrically: once the pattern of choices
    // repeats (or, first, straight after the fresh cut's revolution), find the periodic state by
    // Newton's method; its last step is a plain run from the periodic state, so a success
    // proves itself.
    if (deflect && r >= 1 && newton_wait <= 0) {
      for (int p = 1; p <= r && p * flutes <= kMaxNewtonDim; ++p) {
        const bool repeated = 2 * p <= r && same_codes(r - p, r - 2 * p, p);
        const bool first_try = r == 1 && p == 1;
        if (repeated || first_try) {
          if (newton(slot, first, p, r, len)) {
            store_cycle(slot, nt_records.data(), first, p);
            phase[uslot] = r;
            ++result.stats.newton_slots;
            settle(r);
            return;
          }
          newton_wait = first_try ? 1 : 2 * p;
          break;
        }
      }
    }
    --newton_wait;
    if (r == kMaxSlotRevolutions) {
      // No repetition found: take the last revolution as it stands.
      store_cycle(slot, &trajectory[static_cast<std::size_t>(r - 1) * n], first, 1);
      phase[uslot] = r - 1;
      ++result.stats.unconverged_slots;
      settle(r);
      return;
    }
    // One revolution of passes, flutes in pitch order from `first`.
    for (int q = 0; q < flutes; ++q) {
      const int j = (first + q) % flutes;
      const auto uj = static_cast<std::size_t>(j);
      const std::size_t at = len;
      const PassResult pr = run_pass(j, true, area_input(slot, j), guess[uj], &hist[at - p_len]);
      hist[len] = pr.deficit_um;
      no_cut[len + 1] =
          ((no_cut[len] << 1) | static_cast<std::uint64_t>(pr.deficit_um == kNoCut)) & window_bits;
      ++len;
      const std::size_t k = static_cast<std::size_t>(r) * n + static_cast<std::size_t>(q);
      codes[k] = pr.code;
      trajectory[k] = to_record(pr, deflect, law_kind == ForceLawKind::kPowerLaw);
      if (pr.h_um > 0.0) {
        guess[uj] = pr.log_h_um;
      }
    }
    result.stats.passes += flutes;
  }
}

bool SteadyStateWorkspace::Impl::newton(int slot, int first, int p, int r, std::size_t len) {
  const int m = p * flutes;
  const auto um = static_cast<std::size_t>(m);
  const auto p_len = static_cast<std::size_t>(passes);
  const auto n = static_cast<std::size_t>(flutes);
  double* x = nt_x.data();
  double* y = nt_y.data();
  double* f = nt_f.data();
  double* jac = nt_j.data();
  double* gy = nt_gy.data();
  double* vals = nt_vals.data();
  double* grads = nt_grads.data();
  const unsigned* ref = &codes[static_cast<std::size_t>(r - p) * n];
  for (std::size_t q = 0; q < um; ++q) {
    x[q] = hist[len - um + q];
    nt_h[q] = guess[static_cast<std::size_t>((first + static_cast<int>(q % n)) % flutes)];
  }
  for (int it = 0; it < kMaxNewtonIterations; ++it) {
    // The periodic state x as the ring at the cycle start: pass t back is x[(M − t) mod M].
    std::fill(grads, grads + (p_len + um) * um, 0.0);
    for (std::size_t t = 1; t <= p_len; ++t) {
      const auto idx = static_cast<std::size_t>(positive_mod(m - static_cast<int>(t), m));
      vals[p_len - t] = x[idx];
      if (x[idx] != kNoCut) {
        grads[(p_len - t) * um + idx] = 1.0;
      }
    }
    for (std::size_t q = 0; q < um; ++q) {
      const int j = (first + static_cast<int>(q % n)) % flutes;
      const std::size_t at = p_len + q;
      const PassResult pr = run_pass(j, true, area_input(slot, j), nt_h[q], &vals[at - p_len]);
      if (pr.code != ref[q]) {
        return false;  // the pattern changed: not this cycle
      }
      vals[at] = pr.deficit_um;
      y[q] = pr.deficit_um;
      nt_records[q] = to_record(pr, deflect, law_kind == ForceLawKind::kPowerLaw);
      if (pr.h_um > 0.0) {
        nt_h[q] = pr.log_h_um;
      }
      double* grow = &grads[at * um];
      if (pr.d_deficit != 0.0 && pr.argmin > 0) {
        const double* src = &grads[(at - static_cast<std::size_t>(pr.argmin)) * um];
        for (std::size_t c = 0; c < um; ++c) {
          grow[c] = pr.d_deficit * src[c];
        }
      }
      std::copy(grow, grow + um, gy + q * um);
    }
    result.stats.passes += m;
    double worst = 0.0;
    for (std::size_t q = 0; q < um; ++q) {
      if (x[q] == kNoCut || y[q] == kNoCut) {
        if (x[q] != y[q]) {
          return false;
        }
        f[q] = 0.0;
        continue;
      }
      f[q] = y[q] - x[q];
      worst = std::max(worst, std::fabs(f[q]));
    }
    if (worst <= kDeficitTolerance_um) {
      return true;  // nt_records hold the cycle's passes, run from the periodic state
    }
    // (∂y/∂x − I)·Δ = −(y − x); entries that did not cut stay fixed.
    for (std::size_t q = 0; q < um; ++q) {
      for (std::size_t c = 0; c < um; ++c) {
        jac[q * um + c] = gy[q * um + c] - (q == c ? 1.0 : 0.0);
      }
      if (x[q] == kNoCut) {
        for (std::size_t c = 0; c < um; ++c) {
          jac[q * um + c] = q == c ? 1.0 : 0.0;
        }
      }
      f[q] = -f[q];
    }
    if (!solve_dense(jac, f, m)) {
      return false;
    }
    for (std::size_t q = 0; q < um; ++q) {
      if (x[q] != kNoCut) {
        x[q] += f[q];
      }
    }
  }
  return false;
}

void SteadyStateWorkspace::Impl::compute_cycle_length() {
  long cycle = 1;
  bool exact = true;
  int longest = 1;
  for (int s = 0; s < discs * steps; ++s) {
    const int p = period[static_cast<std::size_t>(s)];
    longest = std::max(longest, p);
    if (exact && p > 1 && cycle % p != 0) {
      cycle = std::lcm(cycle, static_cast<long>(p));
      if (cycle > kMaxCycleRevolutions) {
        exact = false;
      }
    }
  }
  result.cycle_revolutions = exact ? static_cast<int>(cycle) : kMaxCycleRevolutions;
  result.cycle_exact = exact;
  result.stats.longest_slot_period_revolutions = longest;
}

// ---------------------------------------------------------------------------------------------
// Ploughed area ([001] eqs 14-17), continuous formulation (see the header)

void SteadyStateWorkspace::Impl::compute_areas() {
  const int cyc = result.cycle_revolutions;
  const auto n = static_cast<std::size_t>(flutes);
  const auto ucyc = static_cast<std::size_t>(cyc);
  const auto usteps = static_cast<std::size_t>(steps);
  area_cycle = cyc;
  area.resize(static_cast<std::size_t>(discs * steps) * n * ucyc);
  const int total = cyc * steps;
  walk_h.resize(static_cast<std::size_t>(total));
  walk_area.resize(static_cast<std::size_t>(total));
  for (int i = 0; i < discs; ++i) {
    for (int j = 0; j < flutes; ++j) {
      const auto uj = static_cast<std::size_t>(j);
      // Flute j's passes in time order over the cycle: pass q = m·steps + k is slot
      // (start_slot + k) mod steps in revolution m, and its record (m − phase) mod period of
      // that slot's. Gathered (and scattered back below) a tile of slots at a time, revolution by
      // revolution, each slot's record advancing by one a revolution: no division per pass, and
      // neighbouring passes side by side. Pass by pass, with three integer divisions each, this
      // function had been three quarters of the ploughed-area model's evaluation (100 ms; now 40).
      const int start_slot = positive_mod(-land_steps[uj], steps);
      const auto tiles = [&](auto&& visit) {
        std::array<std::size_t, kAreaTile> us{};
        for (std::size_t k0 = 0; k0 < usteps; k0 += kAreaTile) {
          const std::size_t width = std::min(kAreaTile, usteps - k0);
          for (std::size_t kk = 0; kk < width; ++kk) {
            const auto b = static_cast<std::size_t>(start_slot) + k0 + kk;  // < 2·steps
            us[kk] = static_cast<std::size_t>(i) * usteps + (b < usteps ? b : b - usteps);
          }
          visit(k0, width, us);
        }
      };
      tiles([&](std::size_t k0, std::size_t width, const auto& us) {
        std::array<int, kAreaTile> c{}, p{};
        std::array<const PassRecord*, kAreaTile> recs{};
        for (std::size_t kk = 0; kk < width; ++kk) {
          p[kk] = period[us[kk]];
          c[kk] = positive_mod(-phase[us[kk]], p[kk]);
          recs[kk] = &records[static_cast<std::size_t>(record_offset[us[kk]]) + uj];
        }
        for (std::size_t m = 0; m < ucyc; ++m) {
          double* row = &walk_h[m * usteps + k0];
          for (std::size_t kk = 0; kk < width; ++kk) {
            const PassRecord& rec = recs[kk][static_cast<std::size_t>(c[kk]) * n];
            row[kk] = rec.contact != 0 ? rec.h_rigid_um : 0.0;
            c[kk] = c[kk] + 1 == p[kk] ? 0 : c[kk] + 1;
          }
        }
      });
      // Start the walk just after a pass without contact.
      int start = 0;
      for (int q = 0; q < total; ++q) {
        if (walk_h[static_cast<std::size_t>(q)] <= 0.0) {
          start = q + 1;
          break;
        }
      }
      const auto pass = [&](int t) {  // the walk's t-th pass (t < total; start ≤ total)
        const int q = start + t;
        return static_cast<std::size_t>(q < total ? q : q - total);
      };
      const double scale_mm2 =
          1e-3 * radius_mm[static_cast<std::size_t>(i * flutes + j)] * d_phi_rad;  // µm·rad → mm²
      int t = 0;
      while (t < total) {
        const std::size_t q = pass(t);
        if (walk_h[q] <= 0.0) {
          walk_area[q] = 0.0;
          ++t;
          continue;
        }
        // A contact run (one pass of the flute): first its cutting area A_c ([001] eq 14,
        // trapezoids on the rigid chip from 0 at the pass before), its total A_c(π), where its
        // largest chip is (θ_MAX) and the ploughed area when it first reaches h_min (the
        // crossing interpolated between passes: A_pMAX).
        const int run_from = t;
        double running = 0.0;
        double previous = 0.0;
        double sheared_area = -1.0;
        double largest = 0.0;
        int largest_at = t;
        int run_to = t;
        while (run_to < total && walk_h[pass(run_to)] > 0.0) {
          const double h = walk_h[pass(run_to)];
          const double before = running;
          running += 0.5 * (previous + h) * scale_mm2;
          if (sheared_area < 0.0 && h >= h_min_um) {
            const double frac = (h_min_um - previous) / (h - previous);
            sheared_area = before + scale_mm2 * frac * (previous + 0.5 * frac * (h - previous));
          }
          if (h > largest) {
            largest = h;
            largest_at = run_to;
          }
          previous = h;
          ++run_to;
        }
        const double run_total = running;
        // Then the area each pass sees: h ≥ h_min: A_pMAX ([001] eq 16); below h_min before
        // θ_MAX: A_c(θ) (eq 15); after θ_MAX: A_c(π) − A_c(θ) (eq 17).
        running = 0.0;
        previous = 0.0;
        for (int u = run_from; u < run_to; ++u) {
          const std::size_t qq = pass(u);
          const double h = walk_h[qq];
          running += 0.5 * (previous + h) * scale_mm2;
          previous = h;
          double a = running;
          if (h >= h_min_um) {
            a = sheared_area;
          } else if (u > largest_at) {
            a = std::max(0.0, run_total - running);
          }
          walk_area[qq] = a;
        }
        t = run_to;
      }
      // Each pass's area to its slot and revolution.
      tiles([&](std::size_t k0, std::size_t width, const auto& us) {
        for (std::size_t m = 0; m < ucyc; ++m) {
          const double* row = &walk_area[m * usteps + k0];
          for (std::size_t kk = 0; kk < width; ++kk) {
            area[(us[kk] * n + uj) * ucyc + m] = row[kk];
          }
        }
      });
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Forces

void SteadyStateWorkspace::Impl::accumulate_forces(bool with_cycle) {
  const int cyc = result.cycle_revolutions;
  const auto n = static_cast<std::size_t>(flutes);
  const auto s = static_cast<std::size_t>(steps);
  const bool cycle = with_cycle && cyc > 1;
  for (int a = 0; a < 3; ++a) {
    auto& mean = flute_mean[static_cast<std::size_t>(a)];
    std::fill(mean.begin(), mean.end(), 0.0);
    if (cycle) {
      auto& cy = flute_cycle[static_cast<std::size_t>(a)];
      cy.resize(n * s * static_cast<std::size_t>(cyc));
      std::fill(cy.begin(), cy.end(), 0.0);
    }
  }
  auto element = [&](const PassRecord& rec, int j, double area_mm2, double ct, double st,
                     double* xyz) {
    if (rec.contact == 0) {
      xyz[0] = xyz[1] = xyz[2] = 0.0;
      return;
    }
    ElementForce f = law.element_given_log(rec.h_um, rec.log_h_um, dz_mm, area_mm2);
    f.tangential_N += wear_t_N[static_cast<std::size_t>(j)];
    f.normal_N += wear_n_N[static_cast<std::size_t>(j)];
    // [000] eq 7: force on the tool in the workpiece frame.
    xyz[0] = -f.tangential_N * ct - f.normal_N * st;
    xyz[1] = f.tangential_N * st - f.normal_N * ct;
    xyz[2] = f.axial_N;
  };
  auto area_of = [&](std::size_t us, std::size_t j, int m) {
    return area_law ? area[(us * n + j) * static_cast<std::size_t>(area_cycle) +
                           static_cast<std::size_t>(m % area_cycle)]
                    : 0.0;
  };
  auto add = [&](std::array<std::vector<double>, 3>& to, std::size_t at, const double* xyz,
                 double weight) {
    to[0][at] += weight * xyz[0];
    to[1][at] += weight * xyz[1];
    to[2][at] += weight * xyz[2];
  };
  for (int i = 0; i < discs; ++i) {
    for (int b = 0; b < steps; ++b) {
      const auto us = static_cast<std::size_t>(i * steps + b);
      const int p = period[us];
      const PassRecord* rec = &records[static_cast<std::size_t>(record_offset[us])];
      for (int j = 0; j < flutes; ++j) {
        const std::size_t fs = flute_slot(i, j, b);
        if (engaged[fs] == 0) {
          continue;
        }
        const double ct = cos_theta[fs];
        const double st = sin_theta[fs];
        const auto uj = static_cast<std::size_t>(j);
        const std::size_t at = uj * s + static_cast<std::size_t>(b);
        double xyz[3];
        if (area_law && cyc > 1) {
          // The area repeats with the whole cycle: one force per revolution of the cycle, and
          // the mean over the cycle.
          for (int m = 0; m < cyc; ++m) {
            const int c = positive_mod(m - phase[us], p);
            element(rec[static_cast<std::size_t>(c) * n + uj], j, area_of(us, uj, m), ct, st, xyz);
            add(flute_mean, at, xyz, 1.0 / cyc);
            if (cycle) {
              add(flute_cycle, static_cast<std::size_t>(m) * n * s + at, xyz, 1.0);
            }
          }
          continue;
        }
        // The mean over the slot's own cycle (exact whatever L); revolution m of the whole
        // cycle has the slot at phase (m − r_s) mod p_s.
        for (int c = 0; c < p; ++c) {
          if (rec[static_cast<std::size_t>(c) * n + uj].contact == 0) {
            continue;
          }
          element(rec[static_cast<std::size_t>(c) * n + uj], j, area_of(us, uj, 0), ct, st, xyz);
          add(flute_mean, at, xyz, 1.0 / p);
          if (cycle) {
            for (int m = positive_mod(phase[us] + c, p); m < cyc; m += p) {
              add(flute_cycle, static_cast<std::size_t>(m) * n * s + at, xyz, 1.0);
            }
          }
        }
      }
    }
  }
}

void SteadyStateWorkspace::Impl::assemble(std::span<const double> per_flute, int revolutions, int m,
                                          std::span<double> out) const {
  // Flute j's pass of slot b lands at spindle step b + ψ_j/Δφ: linear interpolation onto the
  // grid between the passes landing at k + w_j (slot k − ⌊ψ_j/Δφ⌋) and k − 1 + w_j (one slot
  // earlier; for k = 0 that pass belongs to the previous revolution).
  const auto n = static_cast<std::size_t>(flutes);
  const auto s = static_cast<std::size_t>(steps);
  std::fill(out.begin(), out.end(), 0.0);
  const std::size_t base = static_cast<std::size_t>(m) * n * s;
  const std::size_t prev = static_cast<std::size_t>(positive_mod(m - 1, revolutions)) * n * s;
  for (int j = 0; j < flutes; ++j) {
    const auto uj = static_cast<std::size_t>(j);
    const double w = output_frac[uj];
    const double* row = &per_flute[base + uj * s];
    const double* row_prev = &per_flute[prev + uj * s];
    // Slot of step k: k − off, wrapped; the steps before the wrap and after it in two runs.
    const auto first = static_cast<std::size_t>(positive_mod(-land_steps[uj], steps));
    const std::size_t run = s - first;  // steps 0 .. run−1 read slots first .. s−1
    for (std::size_t k = 0; k < s; ++k) {
      const std::size_t slot = k < run ? first + k : k - run;
      const double here = row[slot];
      if (w == 0.0) {
        out[k] += here;
        continue;
      }
      const double before =
          slot == 0 ? (k == 0 ? row_prev : row)[s - 1] : (k == 0 ? row_prev : row)[slot - 1];
      out[k] += (1.0 - w) * here + w * before;
    }
  }
}

void SteadyStateWorkspace::Impl::apply_dynamometer(std::span<double> waveform, int axis,
                                                   int revolutions) {
  const auto ua = static_cast<std::size_t>(axis);
  const double fn = dyn.natural_hz[ua];
  const double zeta = dyn.damping_ratio[ua];
  auto response = [fn, zeta](double f) { return resonance_response(fn, zeta, f); };
  if (revolutions == 1) {
    mean_response.apply(waveform, spindle_hz, response);
    return;
  }
  auto& r = cycle_response[static_cast<std::size_t>(revolutions)];
  if (r.samples() != revolutions * steps) {
    r = PeriodicResponse(revolutions * steps);  // the first cycle of this length: plans once
  }
  r.apply(waveform, spindle_hz / revolutions, response);
}

void SteadyStateWorkspace::Impl::evaluate(const ModelConfig& c, double rpm, int steps_per_rev,
                                          SteadyStateOutput output, bool forces) {
  result.stats = SteadyStateStats{};
  configure(c, rpm, steps_per_rev);
  result.spindle_rpm = rpm;
  result.steps_per_rev = steps;
  result.stats.slots = discs * steps;

  area_coupled = false;
  result.stats.area_converged = !(area_law && deflect);
  for (int sweep = 0; sweep < (area_law && deflect ? kMaxAreaSweeps : 1); ++sweep) {
    solve_slots();
    compute_cycle_length();
    ++result.stats.area_sweeps;
    if (!area_law) {
      break;
    }
    compute_areas();
    if (!deflect) {
      break;
    }
    // The chips depend on the areas through the deflection: solve again with these areas until
    // they settle.
    double largest = 0.0;
    double change = 0.0;
    const auto cyc = static_cast<std::size_t>(area_cycle);
    for (std::size_t q = 0; q < area_mean.size(); ++q) {
      double sum = 0.0;
      for (std::size_t m = 0; m < cyc; ++m) {
        sum += area[q * cyc + m];
      }
      const double mean = sum / static_cast<double>(cyc);
      largest = std::max(largest, std::fabs(mean));
      change = std::max(change, std::fabs(mean - area_mean_prev[q]));
      area_mean[q] = mean;
    }
    if (area_coupled && change <= kAreaTolerance * std::max(largest, 1e-300)) {
      result.stats.area_converged = true;
      break;
    }
    std::swap(area_mean, area_mean_prev);
    area_coupled = true;
  }
  if (!forces) {
    for (auto* w : {&result.mean.fx_N, &result.mean.fy_N, &result.mean.fz_N, &result.cycle.fx_N,
                    &result.cycle.fy_N, &result.cycle.fz_N}) {
      w->clear();  // not computed: no stale force of an earlier call
    }
    return;
  }
  const bool with_cycle = output == SteadyStateOutput::kMeanAndCycle;
  accumulate_forces(with_cycle);

  const int cyc = result.cycle_revolutions;
  const auto s = static_cast<std::size_t>(steps);
  std::array<std::vector<double>*, 3> mean = {&result.mean.fx_N, &result.mean.fy_N,
                                              &result.mean.fz_N};
  std::array<std::vector<double>*, 3> cycle = {&result.cycle.fx_N, &result.cycle.fy_N,
                                               &result.cycle.fz_N};
  for (int a = 0; a < 3; ++a) {
    const auto ua = static_cast<std::size_t>(a);
    mean[ua]->resize(s);
    assemble(flute_mean[ua], 1, 0, *mean[ua]);
    if (dynamometer) {
      apply_dynamometer(*mean[ua], a, 1);
    }
    if (!with_cycle) {
      cycle[ua]->clear();
      continue;
    }
    cycle[ua]->resize(s * static_cast<std::size_t>(cyc));
    if (cyc == 1) {
      std::copy(mean[ua]->begin(), mean[ua]->end(), cycle[ua]->begin());
      continue;
    }
    for (int m = 0; m < cyc; ++m) {
      assemble(flute_cycle[ua], cyc, m,
               std::span<double>(*cycle[ua]).subspan(static_cast<std::size_t>(m) * s, s));
    }
    if (dynamometer) {
      apply_dynamometer(*cycle[ua], a, cyc);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Basis

void SteadyStateWorkspace::Impl::accumulate_basis() {
  // Columns per law (see evaluate_force_basis); column `columns` is the offset.
  int columns = 0;
  for (const char* n : linear_coefficient_names(law_kind, min_chip, area_law)) {
    basis.names[static_cast<std::size_t>(columns++)] = n;
  }
  const auto& le = material_coefficients.linear_edge;
  const auto& pl = material_coefficients.power_law;
  const auto& kr = material_coefficients.kronenberg;
  basis.columns = columns;
  const auto n = static_cast<std::size_t>(flutes);
  const auto s = static_cast<std::size_t>(steps);
  const auto ncol = static_cast<std::size_t>(columns + 1);
  for (auto& v : basis_flute) {
    std::fill(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(ncol * n * s), 0.0);
  }
  const int cyc = result.cycle_revolutions;
  const bool plough_law = has_plough_law(le);
  // Per element: tangential, normal, axial force of each unit coefficient (column c) and of
  // the offset (column `columns`).
  double tna[kMaxBasisColumns + 1][3];
  auto element = [&](const PassRecord& rec, int j, double area_mm2) {
    for (auto& row : tna) {
      row[0] = row[1] = row[2] = 0.0;
    }
    if (rec.contact == 0) {
      return;
    }
    const auto off = static_cast<std::size_t>(columns);
    tna[off][0] = wear_t_N[static_cast<std::size_t>(j)];
    tna[off][1] = wear_n_N[static_cast<std::size_t>(j)];
    const double h = rec.h_um;
    if (h <= 0.0) {
      return;
    }
    const double h_mm = h * kMmPerUm;
    const bool plough = law.ploughing(h);
    switch (law_kind) {
      case ForceLawKind::kLinearEdge:
        if (area_law) {
          tna[0][0] = h_mm * dz_mm;
          tna[1][1] = h_mm * dz_mm;
          tna[2][2] = h_mm * dz_mm;
          tna[3][0] = area_mm2 * dz_mm;
          tna[4][1] = area_mm2 * dz_mm;
          tna[5][2] = area_mm2 * dz_mm;
        } else if (plough && plough_law) {
          const ElementForce f = law.element(h, dz_mm);  // [002] eq 17: no listed coefficient
          tna[off][0] += f.tangential_N;
          tna[off][1] += f.normal_N;
          tna[off][2] += f.axial_N;
        } else {
          tna[0][0] = h_mm * dz_mm;
          tna[1][1] = h_mm * dz_mm;
          tna[2][2] = h_mm * dz_mm;
          tna[3][0] = dz_mm;
          tna[4][1] = dz_mm;
          tna[5][2] = dz_mm;
        }
        break;
      case ForceLawKind::kPowerLaw: {
        const double log_h_mm = std::log(h_mm);
        const int base = plough ? 3 : 0;
        const double at = plough ? pl.a_tp : pl.a_tc;
        const double an = plough ? pl.a_np : pl.a_nc;
        const double aa = plough ? pl.a_ap : pl.a_ac;
        tna[base + 0][0] = std::exp(at * log_h_mm) * dz_mm;
        tna[base + 1][1] = std::exp(an * log_h_mm) * dz_mm;
        tna[base + 2][2] = std::exp(aa * log_h_mm) * dz_mm;
        break;
      }
      case ForceLawKind::kKronenberg: {
        const ElementForce f = law.element(h, dz_mm);
        const double unit = f.tangential_N / kr.k_s0_N_per_mm2;
        tna[0][0] = unit;
        tna[0][1] = kr.radial_ratio * unit;
        tna[0][2] = kr.axial_ratio * unit;
        break;
      }
    }
  };
  auto area_of = [&](std::size_t us, std::size_t j, int m) {
    return area_law ? area[(us * n + j) * static_cast<std::size_t>(area_cycle) +
                           static_cast<std::size_t>(m % area_cycle)]
                    : 0.0;
  };
  if (law_kind == ForceLawKind::kLinearEdge && !area_law) {
    accumulate_linear_edge_basis(static_cast<std::size_t>(columns), plough_law);
    return;
  }
  for (int i = 0; i < discs; ++i) {
    for (int b = 0; b < steps; ++b) {
      const auto us = static_cast<std::size_t>(i * steps + b);
      const int p = period[us];
      const PassRecord* rec = &records[static_cast<std::size_t>(record_offset[us])];
      // The mean over the slot's own cycle; with the area law over the whole cycle.
      const int evaluations = area_law ? cyc : p;
      for (int j = 0; j < flutes; ++j) {
        const std::size_t el = flute_slot(i, j, b);
        if (engaged[el] == 0) {
          continue;
        }
        const double ct = cos_theta[el];
        const double st = sin_theta[el];
        const auto uj = static_cast<std::size_t>(j);
        const double weight = 1.0 / evaluations;
        for (int e = 0; e < evaluations; ++e) {
          const int c = area_law ? positive_mod(e - phase[us], p) : e;
          element(rec[static_cast<std::size_t>(c) * n + uj], j, area_of(us, uj, e));
          for (std::size_t col = 0; col < ncol; ++col) {
            const double t = tna[col][0] * weight;
            const double nn = tna[col][1] * weight;
            const double a = tna[col][2] * weight;
            if (t == 0.0 && nn == 0.0 && a == 0.0) {
              continue;  // most columns see one axis of one regime
            }
            const std::size_t at = (col * n + uj) * s + static_cast<std::size_t>(b);
            basis_flute[0][at] += -t * ct - nn * st;
            basis_flute[1][at] += t * st - nn * ct;
            basis_flute[2][at] += a;
          }
        }
      }
    }
  }
}

void SteadyStateWorkspace::Impl::accumulate_linear_edge_basis(std::size_t offset_column,
                                                              bool plough_law) {
  // The common case, written out: each column sees one direction of one element. Entry (j, b)
  // of a column sums its discs' elements over their cycles, in registers and in the order the
  // general loop adds them to memory (disc, then revolution): the same sums, bit for bit. The
  // axes a column never sees (fz of K_tc, fx of K_ac, …) keep the caller's zeros.
  const auto n = static_cast<std::size_t>(flutes);
  const auto s = static_cast<std::size_t>(steps);
  const std::size_t stride = n * s;  // one column of basis_flute[axis]
  const std::size_t offset_col = offset_column * stride;
  double* fx = basis_flute[0].data();
  double* fy = basis_flute[1].data();
  double* fz = basis_flute[2].data();
  for (int b = 0; b < steps; ++b) {
    for (int j = 0; j < flutes; ++j) {
      const auto uj = static_cast<std::size_t>(j);
      // Columns K_tc, K_nc, K_ac (cut), K_te, K_ne, K_ae (edge) and the offset (o).
      double tc_x = 0.0, tc_y = 0.0, nc_x = 0.0, nc_y = 0.0, ac_z = 0.0;
      double te_x = 0.0, te_y = 0.0, ne_x = 0.0, ne_y = 0.0, ae_z = 0.0;
      double o_x = 0.0, o_y = 0.0, o_z = 0.0;
      for (int i = 0; i < discs; ++i) {
        const std::size_t el = flute_slot(i, j, b);
        if (engaged[el] == 0) {
          continue;
        }
        const auto us = static_cast<std::size_t>(i * steps + b);
        const int p = period[us];
        const PassRecord* rec = &records[static_cast<std::size_t>(record_offset[us])];
        const double ct = cos_theta[el];
        const double st = sin_theta[el];
        const double weight = 1.0 / p;  // the mean over the slot's own cycle
        for (int e = 0; e < p; ++e) {
          const PassRecord& r = rec[static_cast<std::size_t>(e) * n + uj];
          if (r.contact == 0) {
            continue;
          }
          const double wt = wear_t_N[uj] * weight;
          const double wn = wear_n_N[uj] * weight;
          o_x += -wt * ct - wn * st;
          o_y += wt * st - wn * ct;
          if (r.h_um <= 0.0) {
            continue;
          }
          if (plough_law && law.ploughing(r.h_um)) {
            const ElementForce f = law.element(r.h_um, dz_mm);  // [002] eq 17
            o_x += weight * (-f.tangential_N * ct - f.normal_N * st);
            o_y += weight * (f.tangential_N * st - f.normal_N * ct);
            o_z += weight * f.axial_N;
            continue;
          }
          const double cut = r.h_um * kMmPerUm * dz_mm * weight;  // K_tc, K_nc, K_ac
          const double edge = dz_mm * weight;                     // K_te, K_ne, K_ae
          tc_x += -cut * ct;
          tc_y += cut * st;
          nc_x += -cut * st;
          nc_y += -cut * ct;
          ac_z += cut;
          te_x += -edge * ct;
          te_y += edge * st;
          ne_x += -edge * st;
          ne_y += -edge * ct;
          ae_z += edge;
        }
      }
      const std::size_t at = uj * s + static_cast<std::size_t>(b);
      fx[at] = tc_x;
      fy[at] = tc_y;
      fx[stride + at] = nc_x;
      fy[stride + at] = nc_y;
      fz[2 * stride + at] = ac_z;
      fx[3 * stride + at] = te_x;
      fy[3 * stride + at] = te_y;
      fx[4 * stride + at] = ne_x;
      fy[4 * stride + at] = ne_y;
      fz[5 * stride + at] = ae_z;
      fx[offset_col + at] = o_x;
      fy[offset_col + at] = o_y;
      fz[offset_col + at] = o_z;
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Public

SteadyStateWorkspace::SteadyStateWorkspace() : impl_(std::make_unique<Impl>()) {}

SteadyStateWorkspace::SteadyStateWorkspace(const ModelConfig& config, int steps_per_rev)
    : SteadyStateWorkspace() {
  reserve(config, steps_per_rev);
}

SteadyStateWorkspace::~SteadyStateWorkspace() = default;
SteadyStateWorkspace::SteadyStateWorkspace(SteadyStateWorkspace&&) noexcept = default;
SteadyStateWorkspace& SteadyStateWorkspace::operator=(SteadyStateWorkspace&&) noexcept = default;

void SteadyStateWorkspace::reserve(const ModelConfig& config, int steps_per_rev) {
  impl_->configure(config, config.process.spindle_rpm, steps_per_rev);
  if (impl_->dynamometer && impl_->memory) {
    // Cycles of a few revolutions are the common ones: plan them now.
    for (int cyc = 2; cyc <= 4; ++cyc) {
      auto& r = impl_->cycle_response[static_cast<std::size_t>(cyc)];
      if (r.samples() != cyc * steps_per_rev) {
        r = PeriodicResponse(cyc * steps_per_rev);
      }
    }
  }
}

const SteadyState& SteadyStateWorkspace::result() const {
  return impl_->result;
}

namespace {
const PassRecord& record_at(const std::vector<PassRecord>& records, const std::vector<int>& offset,
                            const std::vector<int>& period, const std::vector<int>& phase,
                            int flutes, int steps, int flute, int slot, long revolution) {
  if (flute < 0 || flute >= flutes || slot < 0 || slot >= steps || revolution < 0) {
    throw std::out_of_range("steady state: flute " + std::to_string(flute) + ", slot " +
                            std::to_string(slot) + ", revolution " + std::to_string(revolution) +
                            " outside the last result");
  }
  const auto us = static_cast<std::size_t>(slot);
  const int c = static_cast<int>(((revolution - phase[us]) % period[us] + period[us]) % period[us]);
  return records[static_cast<std::size_t>(offset[us]) +
                 static_cast<std::size_t>(c * flutes + flute)];
}
}  // namespace

double SteadyStateWorkspace::chip_um(int flute, int slot, long revolution) const {
  const Impl& m = *impl_;
  return record_at(m.records, m.record_offset, m.period, m.phase, m.flutes, m.steps, flute, slot,
                   revolution)
      .h_um;
}

double SteadyStateWorkspace::rigid_chip_um(int flute, int slot, long revolution) const {
  const Impl& m = *impl_;
  return record_at(m.records, m.record_offset, m.period, m.phase, m.flutes, m.steps, flute, slot,
                   revolution)
      .h_rigid_um;
}

bool SteadyStateWorkspace::removed(int flute, int slot, long revolution) const {
  const Impl& m = *impl_;
  return record_at(m.records, m.record_offset, m.period, m.phase, m.flutes, m.steps, flute, slot,
                   revolution)
             .removed != 0;
}

int SteadyStateWorkspace::slot_period_revolutions(int disc, int slot) const {
  const Impl& m = *impl_;
  if (disc < 0 || disc >= m.discs || slot < 0 || slot >= m.steps) {
    throw std::out_of_range("steady state: disc " + std::to_string(disc) + ", slot " +
                            std::to_string(slot) + " outside the last result");
  }
  return m.period[static_cast<std::size_t>(disc * m.steps + slot)];
}

const SteadyState& evaluate_steady_state(const ModelConfig& config, double spindle_rpm,
                                         int steps_per_rev, SteadyStateWorkspace& workspace,
                                         SteadyStateOutput output) {
  workspace.impl_->evaluate(config, spindle_rpm, steps_per_rev, output);
  return workspace.impl_->result;
}

std::span<const char* const> linear_coefficient_names(const ModelConfig& config) {
  const ForceLawKind law = config.material.law;
  return linear_coefficient_names(
      law, config.effects.min_chip.enabled,
      law == ForceLawKind::kLinearEdge && config.material.linear_edge.ploughing_area);
}

const ForceBasis& evaluate_force_basis(const ModelConfig& config, double spindle_rpm,
                                       int steps_per_rev, SteadyStateWorkspace& workspace,
                                       bool with_force) {
  if (config.effects.deflection.enabled) {
    throw std::invalid_argument(
        "evaluate_force_basis: effects.deflection is on; the chips then depend on the "
        "coefficients (the deflection balance, [000] eq 22) and the force is not linear in them");
  }
  SteadyStateWorkspace::Impl& m = *workspace.impl_;
  m.evaluate(config, spindle_rpm, steps_per_rev, SteadyStateOutput::kMean, with_force);
  m.accumulate_basis();
  const auto s = static_cast<std::size_t>(m.steps);
  const auto n = static_cast<std::size_t>(m.flutes);
  for (int col = 0; col <= m.basis.columns; ++col) {
    ForceWaveform& w =
        col < m.basis.columns ? m.basis.unit[static_cast<std::size_t>(col)] : m.basis.offset;
    std::array<std::vector<double>*, 3> axes = {&w.fx_N, &w.fy_N, &w.fz_N};
    for (int a = 0; a < 3; ++a) {
      const auto ua = static_cast<std::size_t>(a);
      axes[ua]->resize(s);
      // assemble() reads one revolution of N·S values at the column's offset.
      const std::span<const double> block(&m.basis_flute[ua][static_cast<std::size_t>(col) * n * s],
                                          n * s);
      m.assemble(block, 1, 0, *axes[ua]);
      if (m.dynamometer) {
        m.apply_dynamometer(*axes[ua], a, 1);
      }
    }
  }
  return m.basis;
}

}  // namespace millwatch::model
