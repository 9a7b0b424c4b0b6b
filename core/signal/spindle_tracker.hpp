#pragma once
// Spindle speed and phase from the force signal ([000] Sect. 5: FFT of the force, 25,252 rpm
// measured at 25,000 commanded).
//
// Every hop, the last window of samples (Hann-windowed, zero-padded to a power of two) is
// transformed with FFTW. The spindle frequency f is the one in the commanded speed's search
// range that maximises the mean spectral magnitude at its harmonics h·f (h = 1..H below
// 0.45·f_s): the tooth-passing harmonics (h a multiple of N_z) dominate, the others come from
// runout. The commanded speed is a hint that settles the octave, not the answer. Each harmonic's
// peak is then interpolated (parabola on the log-magnitude of the zero-padded spectrum) and f is
// the average of (peak frequency)/h weighted by (h·magnitude)², since higher harmonics pin f
// more finely. "Cutting" means the strongest harmonic stands min_snr_db above the median of the
// band — with no periodic force there is no valid speed.
//
// Phase: the complex amplitudes of the fundamental and the tooth harmonic at the window centre
// (a DTFT at exactly h·f) give the spindle angle there; the tooth harmonic pins it to 2π/N_z
// and the fundamental picks the flute. The tracker's angle zero is therefore the phase zero of
// the force's fundamental: arbitrary, but steady while locked. A phase model
// (signal::PhaseModel, in input samples) is locked at the first cutting window; at each later
// window it is re-anchored at the newest sample, continuous there, corrected by part of the
// window's phase error, with the speed's rate of change fitted over the last hops so that
// ramps are followed. A large phase error or the loss of cutting
// drops the lock; the next cutting window locks afresh (a stop/start or feed hold).
//
// setup() creates FFTW plans (not thread-safe: set up trackers from one thread at a time);
// process() never allocates.

#include <fftw3.h>

#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

#include "core/signal/phase_model.hpp"

namespace millwatch::signal {

struct SpindleTrackerConfig {
  double sample_rate_hz = 50000.0;  ///< rate of the samples given to process()
  int flutes = 2;
  double commanded_rpm = 25000.0;
  double search_fraction = 0.15;  ///< search f within commanded·(1 ± this)
  double window_s = 0.25;
  double hop_s = 0.05;
  int max_harmonic = 0;  ///< highest harmonic used; 0 = automatic (4·flutes)
  double min_snr_db =
      12.0;  ///< cutting when the strongest harmonic is this far above the band's median
  double phase_gain = 0.5;  ///< fraction of each window's phase error corrected
};

/// @throws config::ConfigError naming the field.
SpindleTrackerConfig spindle_tracker_config_from_json(const nlohmann::json& j,
                                                      const std::string& path);
nlohmann::json to_json(const SpindleTrackerConfig& c);
/// @throws config::ConfigError naming the field for an inconsistent configuration.
void validate(const SpindleTrackerConfig& c, const std::string& path);

struct SpindleEstimate {
  bool valid = false;  ///< a current speed estimate (cutting, locked)
  bool cutting = false;
  bool relocked = false;  ///< this update started a new lock (new angle reference)
  double spindle_hz = 0.0;
  double spindle_rpm = 0.0;
  double uncertainty_rpm = 0.0;
  double snr_db = 0.0;
  double angle_rad = 0.0;          ///< spindle angle at center_sample, [0, 2π)
  std::int64_t center_sample = 0;  ///< the window's centre, in input samples
  std::int64_t updates = 0;
};

class SpindleTracker {
 public:
  SpindleTracker() = default;
  explicit SpindleTracker(const SpindleTrackerConfig& config) { setup(config); }
  ~SpindleTracker();
  SpindleTracker(const SpindleTracker&) = delete;
  SpindleTracker& operator=(const SpindleTracker&) = delete;

  /// Sizes buffers and plans the FFT. @throws config::ConfigError for a bad configuration.
  void setup(const SpindleTrackerConfig& config);
  /// Consumes samples (any block size); updates the estimate at every hop. Returns the number of
  /// updates made in this call.
  int process(std::span<const double> samples);
  /// Forget everything (after a gap in the stream); sample indices restart at `next_sample`.
  void restart(std::int64_t next_sample);

  [[nodiscard]] const SpindleEstimate& estimate() const { return estimate_; }
  /// The locked phase model in input samples (valid only while locked).
  [[nodiscard]] const PhaseModel& phase() const { return phase_; }
  [[nodiscard]] const SpindleTrackerConfig& config() const { return config_; }
  /// Index of the next input sample.
  [[nodiscard]] std::int64_t next_sample() const { return next_sample_; }

 private:
  void update();
  double harmonic_score(double f_hz) const;
  double magnitude_at(double f_hz) const;
  void release();

  SpindleTrackerConfig config_;
  std::size_t window_ = 0;
  std::size_t fft_size_ = 0;
  std::size_t hop_ = 0;
  int harmonics_ = 0;
  std::vector<double> ring_;  // the last window_ samples
  std::vector<double> hann_;
  std::vector<double> magnitude_;
  std::vector<double> scratch_;  // for the median
  double* fft_in_ = nullptr;
  fftw_complex* fft_out_ = nullptr;
  fftw_plan plan_ = nullptr;

  std::int64_t next_sample_ = 0;
  std::int64_t stream_start_ = 0;  // first sample since the last restart
  std::size_t since_hop_ = 0;
  SpindleEstimate estimate_;
  PhaseModel phase_;
  bool locked_ = false;
  std::array<double, 6> recent_hz_{};  // speeds of the last hops, for the ramp rate
  std::array<double, 6> recent_center_s_{};
  int recent_count_ = 0;
};

}  // namespace millwatch::signal
