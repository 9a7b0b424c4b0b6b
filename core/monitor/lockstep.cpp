#include "core/monitor/lockstep.hpp"

#include <cmath>
#include <complex>
#include <numbers>

#include "core/monitor/extremum.hpp"

namespace millwatch::monitor {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr int kAveragedRevolutions = 8;
constexpr int kWarmUpRevolutions = 30;  // enough for deflection and accumulation to settle

double wrap_2pi(double a) {
  a = std::fmod(a, kTwoPi);
  return a < 0.0 ? a + kTwoPi : a;
}

}  // namespace

Lockstep::Lockstep(const model::ModelConfig& model, const signal::ButterworthDesign& filter,
                   bool zero_phase)
    : commanded_(model), config_(model), filter_(filter), zero_phase_(zero_phase) {}

bool Lockstep::set_spindle_hz(double spindle_hz) {
  if (built_ && std::fabs(spindle_hz - spindle_hz_) <= 0.002 * spindle_hz_) {
    return false;
  }
  spindle_hz_ = spindle_hz;
  const double rpm = 60.0 * spindle_hz;
  config_ = commanded_;
  config_.process.spindle_rpm = rpm;
  // The feed rate is what the control commands: a faster spindle cuts thinner chips.
  config_.process.feed_per_tooth_um =
      commanded_.process.feed_per_tooth_um * commanded_.process.spindle_rpm / rpm;
  model::MillingModel m(config_);
  m.warm_up(kWarmUpRevolutions);
  // Near h_min the two-regime law with deflection and accumulation makes chips differ from pass
  // to pass: the model's typical revolution is the mean of several, like the measured average.
  waveform_ = m.forces();
  for (int r = 1; r < kAveragedRevolutions; ++r) {
    m.step_revolution();
    const auto& f = m.forces();
    for (std::size_t k = 0; k < f.fx_N.size(); ++k) {
      waveform_.fx_N[k] += f.fx_N[k];
      waveform_.fy_N[k] += f.fy_N[k];
      waveform_.fz_N[k] += f.fz_N[k];
    }
  }
  for (auto* axis : {&waveform_.fx_N, &waveform_.fy_N, &waveform_.fz_N}) {
    for (double& v : *axis) {
      v /= kAveragedRevolutions;
    }
  }
  filter_periodic();
  built_ = true;
  return true;
}

void Lockstep::filter_periodic() {
  // Steady state of the causal filter on the periodic model force: each harmonic k of the
  // spindle frequency is multiplied by H(k·f). A DFT by phasor recursion (this runs once per
  // model build, on a few hundred points).
  const std::size_t n = waveform_.fx_N.size();
  const std::size_t half = n / 2;
  const std::array<const std::vector<double>*, 3> in = {&waveform_.fx_N, &waveform_.fy_N,
                                                        &waveform_.fz_N};
  std::vector<std::complex<double>> gain(half + 1);
  for (std::size_t k = 0; k <= half; ++k) {
    const std::complex<double> h = filter_.response(static_cast<double>(k) * spindle_hz_);
    gain[k] = zero_phase_ ? std::norm(h) : h;
  }
  std::vector<std::complex<double>> spectrum(half + 1);
  for (std::size_t a = 0; a < 3; ++a) {
    const std::vector<double>& x = *in[a];
    for (std::size_t k = 0; k <= half; ++k) {
      const std::complex<double> step = std::polar(1.0, -kTwoPi * static_cast<double>(k) / n);
      std::complex<double> rot = 1.0;
      std::complex<double> sum = 0.0;
      for (std::size_t i = 0; i < n; ++i) {
        sum += x[i] * rot;
        rot *= step;
      }
      // Real signal: weight 2 for the harmonics with a mirror image, 1 for DC and Nyquist.
      const double weight = (k == 0 || 2 * k == n) ? 1.0 : 2.0;
      spectrum[k] = weight * sum * gain[k] / static_cast<double>(n);
    }
    filtered_[a].assign(n, 0.0);
    for (std::size_t k = 0; k <= half; ++k) {
      const std::complex<double> step = std::polar(1.0, kTwoPi * static_cast<double>(k) / n);
      std::complex<double> rot = spectrum[k];
      for (std::size_t i = 0; i < n; ++i) {
        filtered_[a][i] += std::real(rot);
        rot *= step;
      }
    }
  }
}

void Lockstep::filtered_on_tracker_grid(int axis, int bins, std::vector<double>& out) const {
  out.resize(static_cast<std::size_t>(bins));
  const auto& w = filtered_[static_cast<std::size_t>(axis)];
  const auto n = static_cast<double>(w.size());
  for (int b = 0; b < bins; ++b) {
    const double model_angle = wrap_2pi(kTwoPi * b / bins + offset_rad_);
    const double pos = model_angle / kTwoPi * n;
    const auto k0 = static_cast<std::size_t>(pos) % w.size();
    const std::size_t k1 = (k0 + 1) % w.size();
    const double f = pos - std::floor(pos);
    out[static_cast<std::size_t>(b)] = w[k0] + f * (w[k1] - w[k0]);
  }
}

bool Lockstep::align(const SyncAverage& measured) {
  if (!built_ || measured.revolutions() == 0) {
    return false;
  }
  const int bins = measured.bins();
  // Model filtered waveform at zero offset on the tracker grid, and the measured average.
  const double saved = offset_rad_;
  offset_rad_ = 0.0;
  std::array<std::vector<double>, 3> model_bins;
  std::array<std::vector<double>, 3> meas_bins;
  for (int a = 0; a < 3; ++a) {
    filtered_on_tracker_grid(a, bins, model_bins[static_cast<std::size_t>(a)]);
    measured.average(a, meas_bins[static_cast<std::size_t>(a)]);
    // Means removed: drift and offsets are not shape.
    for (auto* v :
         {&model_bins[static_cast<std::size_t>(a)], &meas_bins[static_cast<std::size_t>(a)]}) {
      double mean = 0.0;
      for (double x : *v) {
        mean += x;
      }
      mean /= bins;
      for (double& x : *v) {
        x -= mean;
      }
    }
  }
  offset_rad_ = saved;
  // Circular correlation c(s) = Σ_axes Σ_b meas[b]·model[b + s]: the model shifted by s bins.
  std::vector<double> corr(static_cast<std::size_t>(bins), 0.0);
  double norm_m = 0.0, norm_d = 0.0;
  for (int a = 0; a < 3; ++a) {
    const auto& m = meas_bins[static_cast<std::size_t>(a)];
    const auto& d = model_bins[static_cast<std::size_t>(a)];
    for (int b = 0; b < bins; ++b) {
      norm_m += m[static_cast<std::size_t>(b)] * m[static_cast<std::size_t>(b)];
      norm_d += d[static_cast<std::size_t>(b)] * d[static_cast<std::size_t>(b)];
    }
    for (int s = 0; s < bins; ++s) {
      double c = 0.0;
      for (int b = 0; b < bins; ++b) {
        c += m[static_cast<std::size_t>(b)] * d[static_cast<std::size_t>((b + s) % bins)];
      }
      corr[static_cast<std::size_t>(s)] += c;
    }
  }
  int best = 0;
  for (int s = 1; s < bins; ++s) {
    if (corr[static_cast<std::size_t>(s)] > corr[static_cast<std::size_t>(best)]) {
      best = s;
    }
  }
  const Extremum e = refine_extremum(
      [&](std::int64_t s) { return corr[static_cast<std::size_t>(((s % bins) + bins) % bins)]; },
      best, 1, false);
  offset_rad_ = wrap_2pi(kTwoPi * e.position / bins);
  correlation_ =
      corr[static_cast<std::size_t>(best)] / std::sqrt(std::max(norm_m * norm_d, 1e-300));
  aligned_ = true;
  return true;
}

std::array<double, 3> Lockstep::force_at(double tracker_angle_rad) const {
  const double turns = (tracker_angle_rad + offset_rad_) / kTwoPi;
  const std::size_t n = filtered_[0].size();
  const double pos = (turns - std::floor(turns)) * static_cast<double>(n);
  const auto k0 = std::min(static_cast<std::size_t>(pos), n - 1);
  const std::size_t k1 = k0 + 1 == n ? 0 : k0 + 1;
  const double f = pos - static_cast<double>(k0);
  return {filtered_[0][k0] + f * (filtered_[0][k1] - filtered_[0][k0]),
          filtered_[1][k0] + f * (filtered_[1][k1] - filtered_[1][k0]),
          filtered_[2][k0] + f * (filtered_[2][k1] - filtered_[2][k0])};
}

}  // namespace millwatch::monitor
