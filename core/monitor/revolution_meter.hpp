#pragma once
// Measures revolutions on the filtered force: valley-to-valley tooth periods and the phase
// angle α ([001] eq 36, [003] eqs 4-5), and each flute's peak forces and ΔFy ([001] Fig. 5).
//
// Valleys are sought where the valley template and the tracked spindle angle put them (± a
// fraction of a pitch), located to a fraction of a sample by a local polynomial fit on the
// detection signal (the pipeline uses the squared resultant with the channel offsets removed),
// and each measured valley nudges the template (so slow phase drift is followed).
// Flute j's period runs from the valley before its cut to the valley after; a revolution is
// measured once the first valley of the next one has arrived. Flute 0 is CE1 (template), and
//   α = 360°·T_1/T,  ΔFy = |peak Fy of CE1| − |peak Fy of CE2|.
// Peaks are the signed sample of largest magnitude per channel within the flute's period,
// refined by a three-point parabola.

#include <array>
#include <climits>
#include <cstdint>

#include "core/monitor/sample_ring.hpp"
#include "core/monitor/valley_template.hpp"
#include "core/signal/phase_model.hpp"

namespace millwatch::monitor {

using signal::PhaseModel;

struct RevolutionMeasurement {
  std::int64_t sequence = 0;  ///< revolutions measured by this meter since its last restart
  int flutes = 0;
  /// Fractional sample index of each valley: flute j's period is [valley[j], valley[j + 1]];
  /// valley[flutes] is the next revolution's first.
  std::array<double, kMaxFlutes + 1> valley_sample{};
  double period_s = 0.0;
  std::array<double, kMaxFlutes> flute_period_s{};
  double alpha_deg = 0.0;
  /// Signed peak of fx, fy, fz per flute (largest magnitude in the flute's period), N.
  std::array<std::array<double, 3>, kMaxFlutes> peak_N{};
  std::array<double, kMaxFlutes> peak_resultant_N{};
  /// Range (largest minus smallest sample) of fx, fy, fz per flute within its period, N: a
  /// measure of each flute's force that a slowly drifting channel offset does not change.
  std::array<std::array<double, 3>, kMaxFlutes> range_N{};
  double delta_fy_N = 0.0;
  bool valid = false;  ///< every valley a true local minimum
};

struct RevolutionMeterConfig {
  int flutes = 2;
  double sample_rate_hz = 50000.0;
  double search_fraction_of_pitch = 0.3;  ///< valley search half-window
  int fit_half_width = 0;                 ///< parabola half-width in samples; 0 = automatic
  double template_gain = 0.05;            ///< how fast measured valleys move the template
};

class RevolutionMeter {
 public:
  RevolutionMeter() = default;
  /// @param channel_offset first of the ring's four channels to measure: fx, fy, fz and the
  ///        valley-detection signal (smallest at the valleys, e.g. the resultant or its square)
  RevolutionMeter(const RevolutionMeterConfig& config, int channel_offset);

  void set_template(const ValleyTemplate& t) { template_ = t; }
  /// The newest sample the next valley needs (known after advance() waited for it); measuring
  /// exactly when it arrives makes the results independent of how samples come in blocks.
  [[nodiscard]] std::int64_t needed_sample() const { return needed_sample_; }
  [[nodiscard]] const ValleyTemplate& valley_template() const { return template_; }

  /// Measures every revolution whose samples are all in the ring, calling sink(measurement)
  /// for each. Nothing is allocated.
  template <typename Sink>
  void advance(const SampleRing& ring, const PhaseModel& phase, Sink&& sink) {
    while (true) {
      const Step s = step(ring, phase);
      if (s == Step::kWait) {
        return;
      }
      if (s == Step::kRevolution) {
        sink(static_cast<const RevolutionMeasurement&>(measurement_));
      }
    }
  }

  /// Forget the valley sequence (after a gap, a loss of lock, a new template); measure only
  /// revolutions whose samples all come at or after `from_sample`.
  void restart(std::int64_t from_sample = INT64_MIN);

 private:
  enum class Step { kWait, kValley, kRevolution };
  Step step(const SampleRing& ring, const PhaseModel& phase);
  bool find_valley(const SampleRing& ring, const PhaseModel& phase, double* position, bool* ok);
  void measure(const SampleRing& ring);

  RevolutionMeterConfig config_;
  int offset_ = 0;
  ValleyTemplate template_;
  bool started_ = false;
  std::int64_t start_from_ = INT64_MIN;
  std::int64_t needed_sample_ = INT64_MIN;
  std::int64_t next_valley_ = 0;  // index k: flute k mod N, tracker revolution k div N + base
  double base_revolution_ = 0.0;  // tracker revolution (unwrapped turns) of valley k = 0
  std::array<double, kMaxFlutes + 1> valleys_{};
  std::array<bool, kMaxFlutes + 1> valley_ok_{};
  int valleys_found_ = 0;
  RevolutionMeasurement measurement_;
};

}  // namespace millwatch::monitor
