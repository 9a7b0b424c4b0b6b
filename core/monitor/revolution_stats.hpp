#pragma once
// What the pipeline keeps across revolutions: the usual peak force (to tell a revolution that
// did not cut), and α and ΔFy over the last window of valid revolutions ([001]: 30).
// Fixed storage, sized at construction; nothing is allocated per revolution.

#include <array>
#include <vector>

#include "core/monitor/revolution_record.hpp"

namespace millwatch::monitor {

class RevolutionStats {
 public:
  RevolutionStats() = default;
  explicit RevolutionStats(int window_revolutions);

  /// A revolution whose largest flute peak is below this fraction of the usual peak did not cut.
  static constexpr double kIdleFraction = 0.2;
  /// A cutting revolution moves the usual peak by this share of its difference from it,
  /// counting a peak above kMostRise times the usual one as that: the usual peak rises 5 % a
  /// revolution at most. One spike (a knock, a chip striking the dynamometer, a sample at the
  /// amplifier's range: 200 N filtered, against a cut's 2 N) had raised it five-fold, every
  /// revolution after it had been taken for one that did not cut, and the usual peak, which
  /// such revolutions do not move, had held there: the rest of the cut lost.
  static constexpr double kPeakGain = 0.05;
  static constexpr double kMostRise = 2.0;
  /// The first revolutions after a start (a lock: the tracker heard the cut) all cut; the usual
  /// peak starts at their median (the smallest of them until there are three), so that a spike
  /// in one of them does not set it.
  static constexpr int kSeedRevolutions = 3;  // (cutting() takes the median of three)

  /// Whether the revolution cut (true for the first kSeedRevolutions); cutting revolutions
  /// update the usual peak.
  bool cutting(const RevolutionMeasurement& m);
  /// Adds a valid revolution to the window and fills the record's window statistics.
  void add(RevolutionRecord& r);
  /// Running level of the revolutions' largest flute peak, N (0: none yet).
  [[nodiscard]] double typical_peak_N() const { return typical_peak_N_; }
  /// A lock: the window of α and ΔFy, and the usual peak, start again (the spindle tracker
  /// heard the cut: its first revolutions give the usual peak).
  void restart();

 private:
  double typical_peak_N_ = 0.0;
  std::array<double, kSeedRevolutions> seed_N_{};  // the first revolutions' peaks
  int seeded_ = 0;
  std::vector<double> alpha_, delta_fy_;
  int count_ = 0;
  int next_ = 0;
};

}  // namespace millwatch::monitor
