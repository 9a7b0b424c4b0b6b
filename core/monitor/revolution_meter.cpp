#include "core/monitor/revolution_meter.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/monitor/extremum.hpp"

namespace millwatch::monitor {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

double wrap_pi(double a) {
  return a - kTwoPi * std::round(a / kTwoPi);
}

}  // namespace

RevolutionMeter::RevolutionMeter(const RevolutionMeterConfig& config, int channel_offset)
    : config_(config), offset_(channel_offset) {}

void RevolutionMeter::restart(std::int64_t from_sample) {
  start_from_ = from_sample;
  needed_sample_ = INT64_MIN;
  started_ = false;
  valleys_found_ = 0;
}

bool RevolutionMeter::find_valley(const SampleRing& ring, const PhaseModel& phase, double* position,
                                  bool* ok) {
  const int flutes = config_.flutes;
  const int j = static_cast<int>(next_valley_ % flutes);
  const double turns = base_revolution_ + static_cast<double>(next_valley_ / flutes);
  const double angle = template_.angle_rad[static_cast<std::size_t>(j)] + kTwoPi * turns;
  const double predicted = phase.sample_at(angle);
  const double pitch_samples = phase.samples_per_revolution() / flutes;
  const auto half =
      static_cast<std::int64_t>(std::ceil(config_.search_fraction_of_pitch * pitch_samples));
  const int h = config_.fit_half_width > 0
                    ? config_.fit_half_width
                    : std::max(2, static_cast<int>(std::lround(pitch_samples / 7.0)));
  const auto center = static_cast<std::int64_t>(std::llround(predicted));
  if (center + half + 3 * h > ring.newest()) {
    needed_sample_ = center + half + 3 * h;
    *ok = false;
    return false;  // not all samples yet (room for the fit to re-centre)
  }
  if (center - half - h < ring.oldest()) {
    *ok = false;
    *position = predicted;
    return true;  // gone: the valley cannot be measured any more
  }
  const int resultant = offset_ + 3;
  std::int64_t best = center - half;
  for (std::int64_t n = center - half; n <= center + half; ++n) {
    if (ring.at(resultant, n) < ring.at(resultant, best)) {
      best = n;
    }
  }
  const bool interior = best > center - half && best < center + half;
  // Fit around the predicted valley when the data agree with the prediction: a window chosen
  // by the noisy minimum itself leans towards the flatter side of an asymmetric valley (a bias
  // of noise), a window fixed by the prediction does not. Then re-centre on the vertex until
  // the window sits on it, so that the result does not depend on the prediction.
  std::int64_t fit_center = std::llabs(best - center) <= h ? center : best;
  Extremum e =
      refine_extremum([&](std::int64_t n) { return ring.at(resultant, n); }, fit_center, h, true);
  if (e.valid && std::llround(e.position) != fit_center) {
    fit_center = std::llround(e.position);
    if (fit_center - h >= ring.oldest() && fit_center + h <= ring.newest()) {
      e = refine_extremum([&](std::int64_t n) { return ring.at(resultant, n); }, fit_center, h,
                          true);
    }
  }
  *position = e.position;
  *ok = interior && e.valid;
  if (*ok) {
    // Follow slow drift of the valley relative to the tracked angle.
    const double measured = phase.angle_at(e.position) - kTwoPi * turns;
    double& a = template_.angle_rad[static_cast<std::size_t>(j)];
    a += config_.template_gain * wrap_pi(measured - a);
  }
  return true;
}

RevolutionMeter::Step RevolutionMeter::step(const SampleRing& ring, const PhaseModel& phase) {
  const int flutes = config_.flutes;
  if (!phase.valid || !template_.valid || ring.empty() || !std::isfinite(phase.spindle_hz) ||
      !(phase.spindle_hz > 0.0)) {
    needed_sample_ = INT64_MIN;
    return Step::kWait;
  }
  if (!started_) {
    // Start at the first CE1 valley comfortably inside the ring.
    const double margin = 0.5 * phase.samples_per_revolution() / flutes;
    const std::int64_t first = std::max(ring.oldest(), start_from_);
    if (first > ring.newest()) {
      needed_sample_ = first;
      return Step::kWait;
    }
    const double oldest_angle = phase.angle_at(static_cast<double>(first) + margin);
    base_revolution_ = std::ceil((oldest_angle - template_.angle_rad[0]) / kTwoPi);
    next_valley_ = 0;
    valleys_found_ = 0;
    started_ = true;
  }
  double position = 0.0;
  bool ok = false;
  if (!find_valley(ring, phase, &position, &ok)) {
    return Step::kWait;
  }
  valleys_[static_cast<std::size_t>(valleys_found_)] = position;
  valley_ok_[static_cast<std::size_t>(valleys_found_)] = ok;
  ++valleys_found_;
  ++next_valley_;
  if (valleys_found_ < flutes + 1) {
    return Step::kValley;
  }
  measure(ring);
  // The next revolution starts at this one's closing valley.
  valleys_[0] = valleys_[static_cast<std::size_t>(flutes)];
  valley_ok_[0] = valley_ok_[static_cast<std::size_t>(flutes)];
  valleys_found_ = 1;
  return Step::kRevolution;
}

void RevolutionMeter::measure(const SampleRing& ring) {
  const int flutes = config_.flutes;
  RevolutionMeasurement& m = measurement_;
  ++m.sequence;
  m.flutes = flutes;
  m.valid = true;
  for (int j = 0; j <= flutes; ++j) {
    m.valley_sample[static_cast<std::size_t>(j)] = valleys_[static_cast<std::size_t>(j)];
    m.valid = m.valid && valley_ok_[static_cast<std::size_t>(j)];
  }
  const double dt = 1.0 / config_.sample_rate_hz;
  m.period_s = (valleys_[static_cast<std::size_t>(flutes)] - valleys_[0]) * dt;
  for (int j = 0; j < flutes; ++j) {
    const auto uj = static_cast<std::size_t>(j);
    m.flute_period_s[uj] = (valleys_[uj + 1] - valleys_[uj]) * dt;
    // Peaks within the flute's period.
    const auto from = static_cast<std::int64_t>(std::ceil(valleys_[uj]));
    const auto to = static_cast<std::int64_t>(std::floor(valleys_[uj + 1]));
    // Channels fx, fy, fz, then the in-plane resultant √(fx² + fy²) (searched on its square).
    for (int c = 0; c < 4; ++c) {
      auto value = [&](std::int64_t n) {
        if (c < 3) {
          return ring.at(offset_ + c, n);
        }
        const double x = ring.at(offset_, n);
        const double y = ring.at(offset_ + 1, n);
        return std::sqrt(x * x + y * y);
      };
      auto size = [&](std::int64_t n) {
        if (c < 3) {
          return std::fabs(ring.at(offset_ + c, n));
        }
        const double x = ring.at(offset_, n);
        const double y = ring.at(offset_ + 1, n);
        return x * x + y * y;
      };
      std::int64_t best = from;
      double best_size = size(from);
      double lowest = value(from), highest = lowest;
      for (std::int64_t n = from + 1; n <= to; ++n) {
        const double z = size(n);
        if (z > best_size) {
          best_size = z;
          best = n;
        }
        if (c < 3) {
          const double v = value(n);
          lowest = std::min(lowest, v);
          highest = std::max(highest, v);
        }
      }
      if (c < 3) {
        m.range_N[uj][static_cast<std::size_t>(c)] = highest - lowest;
      }
      double peak = value(best);
      if (best > from && best < to) {
        const Extremum e = refine_extremum(value, best, 1, peak < 0.0);
        if (e.valid) {
          peak = e.value;
        }
      }
      if (c < 3) {
        m.peak_N[uj][static_cast<std::size_t>(c)] = peak;
      } else {
        m.peak_resultant_N[uj] = peak;
      }
    }
  }
  m.alpha_deg = flutes >= 2 ? 360.0 * m.flute_period_s[1] / m.period_s : 360.0;
  m.delta_fy_N = flutes >= 2 ? std::fabs(m.peak_N[0][1]) - std::fabs(m.peak_N[1][1]) : 0.0;
}

}  // namespace millwatch::monitor
