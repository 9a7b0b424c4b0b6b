#include "core/signal/fftw_planner.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <complex>
#include <numbers>
#include <thread>
#include <vector>

#include "core/model/periodic_response.hpp"
#include "core/signal/spindle_tracker.hpp"
#include "core/signal/welch_spectrum.hpp"

namespace millwatch::signal {
namespace {

constexpr double kPi = std::numbers::pi;

/// Plans a periodic response of n samples and checks it on a waveform with a known answer: a
/// delay of s samples (gain e^{−2πi·k·s/N} per harmonic) turns cos(2π·3n/N) into
/// cos(2π·3(n − s)/N). Returns the largest error.
double delayed_cosine_error(int n, int s) {
  model::PeriodicResponse r(n);
  std::vector<double> w(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    w[static_cast<std::size_t>(i)] = std::cos(2.0 * kPi * 3.0 * i / n);
  }
  std::vector<std::complex<double>> gains(static_cast<std::size_t>(r.harmonics()));
  for (int k = 0; k < r.harmonics(); ++k) {
    gains[static_cast<std::size_t>(k)] = std::polar(1.0, -2.0 * kPi * k * s / n);
  }
  r.apply(w, gains);
  double error = 0.0;
  for (int i = 0; i < n; ++i) {
    error = std::max(
        error, std::fabs(w[static_cast<std::size_t>(i)] - std::cos(2.0 * kPi * 3.0 * (i - s) / n)));
  }
  return error;
}

// millwatchd makes and destroys FFTW plans in two threads: a reloaded pipeline (its spindle
// tracker and lockstep filter) is built and the old one destroyed in the main thread while the
// sample thread plans for a new speed or cycle length. Done here at once, many times, with many
// transform sizes: every transform must stay right (FFTW's planner is not thread-safe; without
// fftw_planner_mutex() this corrupts the planner's tables). The replay's plots take Welch
// spectra (welch_spectrum.hpp) while the model's builder thread may still plan: they join in
// (a spectrum planned without the lock had left both threads spinning in FFTW's planner).
TEST(FftwPlanner, PlansMadeAndDestroyedInThreeThreadsAtOnceStayCorrect) {
  std::atomic<int> bad{0};
  auto trackers = [&] {
    for (int i = 0; i < 400; ++i) {
      SpindleTrackerConfig c;
      c.sample_rate_hz = 20000.0 + 37.0 * i;  // a different FFT size now and then
      c.commanded_rpm = 15000.0 + 20.0 * i;
      SpindleTracker t(c);
      if (delayed_cosine_error(64 + (i % 97), i % 7) > 1e-9) {
        ++bad;
      }
    }
  };
  auto responses = [&] {
    for (int i = 0; i < 2000; ++i) {
      if (delayed_cosine_error(8 + (i * 7) % 1500, i % 5) > 1e-9) {
        ++bad;
      }
    }
  };
  auto spectra = [&] {
    for (int i = 0; i < 300; ++i) {
      const std::size_t n = 64U << (i % 8);  // a line of 1.5 at bin 5, a mean of 2
      std::vector<double> x(n + 17);
      for (std::size_t k = 0; k < x.size(); ++k) {
        x[k] =
            2.0 + 1.5 * std::cos(2.0 * kPi * 5.0 * static_cast<double>(k) / static_cast<double>(n));
      }
      const AmplitudeSpectrum s = welch_amplitude_spectrum(x, 1000.0, 1 << 15);
      if (s.segment != n || std::fabs(s.amplitude[5] - 1.5) > 0.05) {
        ++bad;
      }
    }
  };
  std::thread a(trackers);
  std::thread b(responses);
  std::thread c(spectra);
  a.join();
  b.join();
  c.join();
  EXPECT_EQ(bad.load(), 0);
}

}  // namespace
}  // namespace millwatch::signal
