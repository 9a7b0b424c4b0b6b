#include "core/model/milling_model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace millwatch::model {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kNoCut = std::numeric_limits<double>::infinity();
const double kLogFloor = std::log(1e-6);  // the deflection solve's floor: 1e-6 of the rigid chip

double wrap_2pi(double a) {
  a = std::fmod(a, 2.0 * kPi);
  return a < 0.0 ? a + 2.0 * kPi : a;
}

}  // namespace

MillingModel::MillingModel(const ModelConfig& config) : config_(config) {
  validate(config_);
  derive(false);
}

void MillingModel::update(const ModelConfig& config) {
  validate(config);
  const bool same_shape =
      config.tool.flutes == config_.tool.flutes &&
      config.resolution.steps_per_rev == config_.resolution.steps_per_rev &&
      (config.effects.helix_lag.enabled ? config.effects.helix_lag.discs : 1) == discs_ &&
      passes_to_look_back(config) == passes_;
  config_ = config;
  derive(same_shape);
}

void MillingModel::allocate() {
  const auto s = static_cast<std::size_t>(steps_);
  const auto f = static_cast<std::size_t>(flutes_);
  const auto d = static_cast<std::size_t>(discs_);
  cos_phi_.resize(s);
  sin_phi_.resize(s);
  cos_offset_.resize(d * f);
  sin_offset_.resize(d * f);
  disc_angles_rad_.reserve(d);
  geometry_disc_angles_rad_.reserve(d);
  if (config_.effects.runout.helix == RunoutHelix::kRigidAxis) {
    geometry_.reserve(flutes_, passes_, steps_, discs_);  // runout switched on allocates nothing
  }
  lag_steps_.resize(d);
  lag_floor_.resize(d);
  lag_frac_.resize(d);
  deficit_um_.assign(d * s * static_cast<std::size_t>(passes_), 0.0);
  ring_head_.assign(d * s, 0);
  engaged_.assign(d * s, 0);
  area_cut_mm2_.assign(d * f, 0.0);
  area_plough_max_mm2_.assign(d * f, 0.0);
  area_total_prev_mm2_.assign(d * f, 0.0);
  sheared_.assign(d * f, 0);
  in_contact_.assign(d * f, 0);
  last_deflection_um_.assign(d * f, 0.0);
  forces_.fx_N.assign(s, 0.0);
  forces_.fy_N.assign(s, 0.0);
  forces_.fz_N.assign(s, 0.0);
  previous_fx_N_.assign(s, 0.0);
  previous_fy_N_.assign(s, 0.0);
  chip_.assign(s * f, 0.0);
  removed_.assign(s * f, 0);
}

void MillingModel::derive(bool keep_state) {
  const ModelConfig& c = config_;
  const Effects& e = c.effects;
  flutes_ = c.tool.flutes;
  steps_ = c.resolution.steps_per_rev;
  discs_ = e.helix_lag.enabled ? e.helix_lag.discs : 1;
  passes_ = passes_to_look_back(c);
  d_phi_rad_ = 2.0 * kPi / steps_;
  dz_mm_ = c.process.axial_depth_mm / discs_;
  step_time_s_ = 60.0 / (c.process.spindle_rpm * steps_);
  if (!keep_state) {
    allocate();
  }

  // Pitch snapped to the grid so that every flute passes the same immersion steps.
  bool pitch_changed = pitch_steps_.size() != static_cast<std::size_t>(flutes_);
  flute_pitch_angles_rad(c.tool, pitch_rad_);
  pitch_steps_.resize(pitch_rad_.size());
  for (std::size_t j = 0; j < pitch_rad_.size(); ++j) {
    const int snapped = static_cast<int>(std::lround(pitch_rad_[j] / d_phi_rad_)) % steps_;
    pitch_changed = pitch_changed || snapped != pitch_steps_[j];
    pitch_steps_[j] = snapped;
    pitch_rad_[j] = pitch_steps_[j] * d_phi_rad_;
  }

  const double radius_um = tool_radius_um(c);
  PathGeometry path;
  path.radius_um = radius_um;
  path.feed_per_rad_um = c.process.feed_per_tooth_um * flutes_ / (2.0 * kPi);
  path.offset_um = e.runout.enabled ? e.runout.offset_um : 0.0;
  path.offset_angle_rad = e.runout.enabled ? e.runout.angle_rad : 0.0;

  // Engaged immersion range: [000] eq 28 for side milling, [0, π] for a slot.
  const EngagedArc arc = engaged_arc(c);
  engage_from_rad_ = arc.from_rad;
  engage_to_rad_ = arc.to_rad;
  const double beta = helix_lag_total_rad(c);
  runout_disc_angles_rad(c, disc_angles_rad_);
  const double margin_rad = 4.0 * d_phi_rad_;
  const GeometryKey key{path,   e.trochoidal.enabled,          passes_,
                        steps_, engage_from_rad_ - margin_rad, engage_to_rad_ + beta + margin_rad};
  if (!keep_state || !(key == geometry_key_) || pitch_changed ||
      disc_angles_rad_ != geometry_disc_angles_rad_) {
    // The Newton tables are the costly part of an update: redo them only when the path changed.
    geometry_.configure(path, pitch_rad_, passes_, steps_, e.trochoidal.enabled,
                        key.window_from_rad, key.window_to_rad, disc_angles_rad_);
    geometry_key_ = key;
    geometry_disc_angles_rad_ = disc_angles_rad_;  // same size after the first time
  }

  h_min_um_ = e.min_chip.enabled ? e.min_chip.h_min_um : 0.0;
  law_ = ForceLaw(c.material, c.process.axial_depth_mm, h_min_um_, e.min_chip.enabled);
  disc_stiffness_N_per_um_ = e.deflection.stiffness_N_per_um / discs_;

  for (int i = 0; i < discs_; ++i) {
    const double lag = (i + 0.5) * beta / discs_;
    lag_steps_[static_cast<std::size_t>(i)] = lag / d_phi_rad_;
    const double back = std::floor(-lag / d_phi_rad_);
    lag_floor_[static_cast<std::size_t>(i)] = static_cast<int>(back);
    lag_frac_[static_cast<std::size_t>(i)] = -lag / d_phi_rad_ - back;
    for (int j = 0; j < flutes_; ++j) {
      const auto idx = static_cast<std::size_t>(i * flutes_ + j);
      cos_offset_[idx] = std::cos(pitch_rad_[static_cast<std::size_t>(j)] + lag);
      sin_offset_[idx] = std::sin(pitch_rad_[static_cast<std::size_t>(j)] + lag);
    }
    for (int b = 0; b < steps_; ++b) {
      const double theta = wrap_2pi(b * d_phi_rad_ - lag);
      engaged_[static_cast<std::size_t>(i * steps_ + b)] =
          theta >= engage_from_rad_ && theta <= engage_to_rad_ ? 1 : 0;
    }
  }
  for (int k = 0; k < steps_; ++k) {
    cos_phi_[static_cast<std::size_t>(k)] = std::cos(k * d_phi_rad_);
    sin_phi_[static_cast<std::size_t>(k)] = std::sin(k * d_phi_rad_);
  }

  wear_t_N_.assign(static_cast<std::size_t>(flutes_), 0.0);
  wear_n_N_.assign(static_cast<std::size_t>(flutes_), 0.0);
  if (e.flank_wear.enabled) {
    for (int j = 0; j < flutes_; ++j) {
      const auto& w = e.flank_wear.wear_um;
      const double vb_mm = 1e-3 * (w.size() == 1 ? w[0] : w[static_cast<std::size_t>(j)]);
      wear_t_N_[static_cast<std::size_t>(j)] = e.flank_wear.k_wt_N_per_mm2 * vb_mm * dz_mm_;
      wear_n_N_[static_cast<std::size_t>(j)] = e.flank_wear.k_wn_N_per_mm2 * vb_mm * dz_mm_;
    }
  }
  tool_radius_mm_.resize(static_cast<std::size_t>(discs_ * flutes_));
  for (int i = 0; i < discs_; ++i) {
    for (int j = 0; j < flutes_; ++j) {
      tool_radius_mm_[static_cast<std::size_t>(i * flutes_ + j)] =
          1e-3 * geometry_.flutes_at(i)[static_cast<std::size_t>(j)].radius_um;
    }
  }

  if (e.dynamometer.enabled) {
    const double fs = 1.0 / step_time_s_;
    for (int a = 0; a < 3; ++a) {
      const auto ua = static_cast<std::size_t>(a);
      const Resonance r(e.dynamometer.natural_hz[ua], e.dynamometer.damping_ratio[ua], fs);
      if (keep_state) {
        dynamometer_.axis[ua].retune(r);  // the resonance keeps ringing through the update
      } else {
        dynamometer_.axis[ua] = r;
      }
    }
  }
}

void MillingModel::reset() {
  std::fill(deficit_um_.begin(), deficit_um_.end(), 0.0);
  std::fill(ring_head_.begin(), ring_head_.end(), 0);
  std::fill(area_cut_mm2_.begin(), area_cut_mm2_.end(), 0.0);
  std::fill(area_plough_max_mm2_.begin(), area_plough_max_mm2_.end(), 0.0);
  std::fill(area_total_prev_mm2_.begin(), area_total_prev_mm2_.end(), 0.0);
  std::fill(sheared_.begin(), sheared_.end(), 0);
  std::fill(in_contact_.begin(), in_contact_.end(), 0);
  std::fill(last_deflection_um_.begin(), last_deflection_um_.end(), 0.0);
  for (auto& r : dynamometer_.axis) {
    r.reset();
  }
}

int MillingModel::settling_revolutions() const {
  int revs = (passes_ + flutes_ - 1) / flutes_ + 2;
  if (config_.effects.dynamometer.enabled) {
    double decay_s = 0.0;
    for (const auto& r : dynamometer_.axis) {
      decay_s = std::max(decay_s, r.decay_time_s());
    }
    const double rev_s = step_time_s_ * steps_;
    revs = std::max(revs, static_cast<int>(std::ceil(8.0 * decay_s / rev_s)) + 1);
  }
  return revs;
}

void MillingModel::warm_up(int revolutions, double tolerance) {
  if (revolutions > 0) {
    for (int r = 0; r < revolutions; ++r) {
      step_revolution();
    }
    return;
  }
  // Deflection near the entry and exit, where chips are tiny, relaxes slowly (the leftover
  // grows by a factor F_n'/(k + F_n') → 1 per pass): continue until a revolution repeats the
  // previous one. Accumulation patterns spanning several revolutions never do: hence the cap.
  constexpr int kMaxRevolutions = 150;
  const int settle = settling_revolutions();
  for (int r = 0; r < kMaxRevolutions; ++r) {
    previous_fx_N_ = forces_.fx_N;  // same size: no allocation
    previous_fy_N_ = forces_.fy_N;
    step_revolution();
    double change = 0.0;
    double scale = 0.0;
    for (std::size_t k = 0; k < forces_.fx_N.size(); ++k) {
      change = std::max({change, std::fabs(forces_.fx_N[k] - previous_fx_N_[k]),
                         std::fabs(forces_.fy_N[k] - previous_fy_N_[k])});
      scale = std::max({scale, std::fabs(forces_.fx_N[k]), std::fabs(forces_.fy_N[k])});
    }
    if (r + 1 >= settle && change <= tolerance * scale) {
      return;
    }
  }
}

bool MillingModel::straddles_regime_jump(double h_rigid_um, double lo_log_um, double hi_log_um,
                                         double wear_normal_N, double area_mm2) const {
  if (h_min_um_ <= 0.0 || std::log(h_min_um_) <= lo_log_um || std::log(h_min_um_) >= hi_log_um) {
    return false;
  }
  const double k = disc_stiffness_N_per_um_;
  auto excess = [&](double h) {
    return h + (law_.normal_N(h, dz_mm_, area_mm2) + wear_normal_N) / k - h_rigid_um;
  };
  return excess(h_min_um_ * (1.0 - 1e-12)) < 0.0 && excess(h_min_um_) > 0.0;
}

double MillingModel::solve_deflection(double h_rigid_um, double guess_um, double wear_normal_N,
                                      double area_mm2, double* log_h_um) const {
  // [000] eq 22 (plus the rubbing normal force), as h + (F_n(h) + F_w)/k = h_r for the cut chip
  // h ∈ (0, h_r]. The left side increases with h. F_n ∝ h^a with a < 1 is steep near zero, so
  // Newton runs on u = ln h, where it is well conditioned; a bracket in u catches the jump of
  // F_n at h_min (bisection there).
  const double k = disc_stiffness_N_per_um_;
  const double inv_k = 1.0 / k;
  if (wear_normal_N >= k * h_rigid_um) {
    return 0.0;  // the rubbing force alone pushes the tool back beyond this chip
  }
  double hi = std::log(h_rigid_um);
  const double floor_log = hi + kLogFloor;  // ln(1e-6·h_r)
  bool floor_checked = false;
  double lo = floor_log;
  // Clamped to the bracket in u, by its own ends (ln(1e-6·h_r) and lo may differ in the last
  // bit); the floor in h keeps the logarithm's argument positive.
  double u = std::clamp(std::log(std::max(guess_um, 1e-6 * h_rigid_um)), lo, hi);
  for (int it = 0; it < 60; ++it) {
    const double h = std::exp(u);
    const auto fs = law_.normal_with_slope(h, u, dz_mm_, area_mm2);
    const double g = h + (fs.force_N + wear_normal_N) * inv_k - h_rigid_um;
    if (g > 0.0) {
      hi = u;
    } else {
      lo = u;
    }
    const double step = g / (h + fs.d_du_N * inv_k);
    const double next = u - step;
    if (next > lo && next < hi) {
      if (std::fabs(step) < 1e-4) {
        // Quadratic convergence: the relative error left is ~step². e^{u − s} from h = e^u to
        // within s⁴/24 < 5e-18.
        *log_h_um = next;
        return h * (1.0 - step * (1.0 - step * (0.5 - step / 6.0)));
      }
      u = next;
    } else if (straddles_regime_jump(h_rigid_um, lo, hi, wear_normal_N, area_mm2)) {
      *log_h_um = std::log(h_min_um_);
      return h_min_um_;  // the root sits in F_n's jump: the chip stays at h_min
    } else if (!floor_checked && lo == floor_log) {
      floor_checked = true;
      const double h0 = std::exp(floor_log);
      if (h0 + (law_.normal_N(h0, dz_mm_, area_mm2) + wear_normal_N) / k >= h_rigid_um) {
        return 0.0;  // the tool is pushed back before it cuts anything worth counting
      }
      u = 0.5 * (lo + hi);
    } else {
      u = 0.5 * (lo + hi);
      if (hi - lo < 1e-9) {
        break;
      }
    }
  }
  *log_h_um = u;
  return u <= floor_log + 1e-6 ? 0.0 : std::exp(u);
}

void MillingModel::march_step(int k) {
  const Effects& e = config_.effects;
  const auto uk = static_cast<std::size_t>(k);
  double fx = 0.0, fy = 0.0, fz = 0.0;
  const bool deflect = e.deflection.enabled;
  const bool accumulate = e.accumulation.enabled;
  const bool area_law = law_.uses_ploughed_area();

  for (int i = 0; i < discs_; ++i) {
    // The disc reads the chip tables at k − lag_i, between steps k0 and k1.
    int k0 = k + lag_floor_[static_cast<std::size_t>(i)];
    if (k0 < 0) {
      k0 += steps_;
    }
    const int k1 = k0 + 1 == steps_ ? 0 : k0 + 1;
    const double w = lag_frac_[static_cast<std::size_t>(i)];
    auto table_chip = [&](const double* row) { return row[k0] + w * (row[k1] - row[k0]); };
    const std::ptrdiff_t stride = geometry_.pass_stride();
    for (int j = 0; j < flutes_; ++j) {
      const auto ij = static_cast<std::size_t>(i * flutes_ + j);
      const auto uj = static_cast<std::size_t>(j);
      int b = k - pitch_steps_[uj];
      if (b < 0) {
        b += steps_;
      }
      const auto slot = static_cast<std::size_t>(i * steps_ + b);
      double* ring = &deficit_um_[slot * static_cast<std::size_t>(passes_)];
      const int head = ring_head_[slot];

      // cos/sin of the immersion θ = φ − (ψ_j + lag_i)
      const double ct = cos_phi_[uk] * cos_offset_[ij] + sin_phi_[uk] * sin_offset_[ij];
      const double st = sin_phi_[uk] * cos_offset_[ij] - cos_phi_[uk] * sin_offset_[ij];
      const bool engaged = engaged_[slot] != 0;

      double h_rigid = 0.0;
      if (engaged) {
        h_rigid = kNoCut;
        const double* row = geometry_.row(j, 1, i);  // pass n back: row + (n − 1)·stride
        for (int n = 1, at = head; n <= passes_;
             ++n, at = at == 0 ? passes_ - 1 : at - 1, row += stride) {
          // Pass n back: (head − (n − 1)) mod P. A pass that removed nothing left kNoCut (+∞),
          // which the minimum passes over without a branch.
          h_rigid = std::min(h_rigid, table_chip(row) + ring[at]);
        }
        if (h_rigid == kNoCut) {  // no pass in the window removed material: take the oldest
          h_rigid = table_chip(geometry_.row(j, passes_, i));
        }
        h_rigid = std::max(h_rigid, 0.0);
      }

      double new_deficit = 0.0;
      double h = 0.0;
      bool removed = false;
      if (h_rigid > 0.0) {
        double area = 0.0;
        if (area_law) {
          // [001] eqs 14-17: ploughed area of this pass so far.
          if (in_contact_[ij] == 0) {
            area_cut_mm2_[ij] = 0.0;
            sheared_[ij] = 0;
          }
          area_cut_mm2_[ij] += 1e-3 * h_rigid * tool_radius_mm_[ij] * d_phi_rad_;
          if (sheared_[ij] == 0) {
            if (h_rigid < h_min_um_) {
              area = area_cut_mm2_[ij];
            } else {
              sheared_[ij] = 1;
              area_plough_max_mm2_[ij] = area_cut_mm2_[ij];
              area = area_plough_max_mm2_[ij];
            }
          } else {
            area = h_rigid >= h_min_um_
                       ? area_plough_max_mm2_[ij]
                       : std::max(0.0, area_total_prev_mm2_[ij] - area_cut_mm2_[ij]);
          }
        }
        double log_h = 0.0;
        if (deflect) {
          // Start from this element's deflection one step earlier: it varies smoothly.
          h = solve_deflection(h_rigid, h_rigid - last_deflection_um_[ij], wear_n_N_[uj], area,
                               &log_h);
          last_deflection_um_[ij] = h_rigid - h;
        } else {
          h = h_rigid;
        }
        const bool ploughing = law_.ploughing(h);
        removed = !(accumulate && ploughing);
        new_deficit = removed ? h_rigid - h : kNoCut;
        if (!deflect || h <= 0.0) {
          log_h = h > 0.0 ? std::log(h) : 0.0;
        }
        ElementForce f = law_.element_given_log(h, log_h, dz_mm_, area);
        f.tangential_N += wear_t_N_[uj];
        f.normal_N += wear_n_N_[uj];
        // [000] eq 7: force on the tool in the workpiece frame.
        fx += -f.tangential_N * ct - f.normal_N * st;
        fy += f.tangential_N * st - f.normal_N * ct;
        fz += f.axial_N;
        in_contact_[ij] = 1;
      } else if (in_contact_[ij] != 0) {
        in_contact_[ij] = 0;
        area_total_prev_mm2_[ij] = area_cut_mm2_[ij];
      }

      const int next = head + 1 == passes_ ? 0 : head + 1;
      ring[next] = new_deficit;
      ring_head_[slot] = next;
      if (i == 0) {
        chip_[uj * static_cast<std::size_t>(steps_) + uk] = h;
        removed_[uj * static_cast<std::size_t>(steps_) + uk] = removed ? 1 : 0;
      }
    }
  }

  if (e.dynamometer.enabled) {
    fx = dynamometer_.axis[0].step(fx);
    fy = dynamometer_.axis[1].step(fy);
    fz = dynamometer_.axis[2].step(fz);
  }
  forces_.fx_N[uk] = fx;
  forces_.fy_N[uk] = fy;
  forces_.fz_N[uk] = fz;
}

void MillingModel::step_revolution() {
  for (int k = 0; k < steps_; ++k) {
    march_step(k);
  }
}

}  // namespace millwatch::model
