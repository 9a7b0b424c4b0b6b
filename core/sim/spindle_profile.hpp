#pragma once
// Actual spindle speed over a simulated recording: piecewise linear in time, integrated exactly
// for the spindle angle. Built from the scenario's steady, ramp or stop/start profile.

#include <vector>

#include "core/sim/scenario.hpp"

namespace millwatch::sim {

class SpindleProfile {
 public:
  explicit SpindleProfile(const Scenario& scenario);

  /// Speed at time t (rpm).
  [[nodiscard]] double rpm_at(double time_s) const;
  /// Revolutions turned since t = 0 (∫ rpm/60 dt).
  [[nodiscard]] double revolutions_at(double time_s) const;
  /// Whether the tool is cutting at t: not while a stop/start (feed hold) is under way.
  [[nodiscard]] bool cutting_at(double time_s) const;

 private:
  [[nodiscard]] std::size_t segment(double time_s) const;

  std::vector<double> knot_s_;     // times of the knots, increasing, first 0
  std::vector<double> knot_rpm_;   // speed at each knot
  std::vector<double> knot_revs_;  // revolutions turned at each knot
  double pause_from_s_ = 0.0;
  double pause_to_s_ = -1.0;
};

}  // namespace millwatch::sim
