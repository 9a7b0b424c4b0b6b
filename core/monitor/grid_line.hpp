#pragma once
// A line of positions on a cyclic grid of `grid` points: sample i at start + step·i, for a
// spindle's line (0 ≤ step < grid: forwards, less than a turn a sample). The position advances
// by a step and is wrapped once a turn, instead of a division and a floor per sample; at() must
// be called for i = 0, 1, 2, … in order. The synchronous average's bins and the lockstep model's
// table walk it.

#include <cstdint>

namespace millwatch::monitor {

class GridLine {
 public:
  /// @param start_points the first sample's position, already in [0, grid]
  GridLine(double start_points, double step_points, double grid_points)
      : grid_(grid_points), start_(start_points), step_(step_points) {}

  /// Sample i's position in [0, grid].
  double at(std::int64_t i) {
    double pos = start_ + step_ * static_cast<double>(i) - wrapped_;
    if (pos >= grid_) {
      wrapped_ += grid_;
      pos -= grid_;
    }
    return pos;
  }

 private:
  double grid_;
  double start_;
  double step_;
  double wrapped_ = 0.0;  // whole turns of the grid passed, in grid points
};

}  // namespace millwatch::monitor
