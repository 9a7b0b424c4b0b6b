#include "core/sim/spindle_profile.hpp"

#include <algorithm>

namespace millwatch::sim {

SpindleProfile::SpindleProfile(const Scenario& s) {
  const double rpm = actual_rpm(s);
  const auto& p = s.spindle;
  auto knot = [&](double t, double r) {
    knot_s_.push_back(t);
    knot_rpm_.push_back(r);
  };
  knot(0.0, rpm);
  switch (p.profile) {
    case SpindleProfileKind::kRamp:
      knot(p.ramp_start_s, rpm);
      knot(p.ramp_end_s, p.ramp_end_rpm);
      break;
    case SpindleProfileKind::kStopStart:
      knot(p.stop_s, rpm);
      knot(p.stop_s + p.stop_ramp_s, 0.0);
      knot(p.stop_s + p.stop_ramp_s + p.stop_hold_s, 0.0);
      knot(p.stop_s + 2.0 * p.stop_ramp_s + p.stop_hold_s, rpm);
      pause_from_s_ = p.stop_s;
      pause_to_s_ = p.stop_s + 2.0 * p.stop_ramp_s + p.stop_hold_s;
      break;
    case SpindleProfileKind::kSteady:
      break;
  }
  knot_revs_.assign(knot_s_.size(), 0.0);
  for (std::size_t i = 1; i < knot_s_.size(); ++i) {
    knot_revs_[i] = knot_revs_[i - 1] +
                    (knot_s_[i] - knot_s_[i - 1]) * (knot_rpm_[i] + knot_rpm_[i - 1]) / 120.0;
  }
}

std::size_t SpindleProfile::segment(double t) const {
  const auto it = std::upper_bound(knot_s_.begin(), knot_s_.end(), t);
  return static_cast<std::size_t>(std::max<std::ptrdiff_t>(0, it - knot_s_.begin() - 1));
}

double SpindleProfile::rpm_at(double t) const {
  const std::size_t i = segment(t);
  if (i + 1 >= knot_s_.size()) {
    return knot_rpm_.back();
  }
  const double w = (t - knot_s_[i]) / (knot_s_[i + 1] - knot_s_[i]);
  return knot_rpm_[i] + w * (knot_rpm_[i + 1] - knot_rpm_[i]);
}

double SpindleProfile::revolutions_at(double t) const {
  const std::size_t i = segment(t);
  const double dt = t - knot_s_[i];
  return knot_revs_[i] + dt * (knot_rpm_[i] + rpm_at(t)) / 120.0;
}

bool SpindleProfile::cutting_at(double t) const {
  return !(t >= pause_from_s_ && t < pause_to_s_);
}

}  // namespace millwatch::sim
