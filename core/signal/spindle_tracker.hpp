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
// more finely. "Cutting" means the harmonics stand min_snr_db above their neighbourhoods (the
// sum of their peaks over the sum of their floors; a floor is the median magnitude within two
// spindle frequencies of the harmonic, outside every harmonic's main lobe): spectral lines, not
// a hump of coloured noise — with no periodic force there is no valid speed.
//
// Phase: the complex amplitudes of the fundamental and the tooth harmonic at the window centre
// (a DTFT at exactly h·f) give the spindle angle there; the tooth harmonic pins it to 2π/N_z
// and the fundamental picks the flute. The tracker's angle zero is therefore the phase zero of
// the force's fundamental: arbitrary, but steady while locked.
//
// Quality and locking: every window's estimate carries its SNR (the strongest harmonic over the
// band's median) and its agreement with the window one window length earlier — which shares
// no samples with it (relative speed difference, and the tooth-harmonic phase against the one
// the earlier window predicts at this window's centre at the mean of the two speeds, exact on a
// linear ramp). The tracker locks only on a consistent estimate: two such cutting windows whose
// speeds agree within lock_agreement and whose tooth phases agree within lock_phase_rad — or,
// on a ramp that moves the speed by more than that in a window, three windows a window apart
// whose speeds lie on one line within lock_agreement and whose two pairs of tooth phases each
// agree. A stopping or starting spindle, or weak irregular cutting, gives windows that disagree:
// no lock, no speed. A spindle outside the search can give windows that agree on an alias (its
// harmonics falling on some of a searched speed's): a lock also needs a line at its own
// frequency or its tooth-passing one, and a spindle's strongest line among its harmonics;
// unlocked windows show a spindle's line no searched speed explains (SpindleEstimate).
// While locked, the phase model (signal::PhaseModel, in input samples) is re-anchored at the
// newest sample every window, continuous there, corrected by part of the window's tooth-phase
// error (modulo one pitch, so a weak fundamental cannot flip the flute), with the speed's rate
// of change fitted over the last windows so that ramps are followed. A large phase error or the
// loss of cutting drops the lock; the next consistent pair of windows locks afresh.
//
// The window is short by default (10 revolutions at the commanded speed, 0.02–0.25 s) so that
// a stop/start re-acquires within a tenth of a second and a ramp barely moves the speed within
// one window; the monitor measures each revolution's own speed from its tooth events, so the
// tracker needs to be consistent, not precise.
//
// setup() creates an FFTW plan (under fftw_planner_mutex(): trackers may be set up and destroyed
// in any thread); process() never allocates and takes no lock.

#include <fftw3.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

#include "core/signal/harmonic_floors.hpp"
#include "core/signal/phase_model.hpp"

namespace millwatch::signal {

struct SpindleTrackerConfig {
  double sample_rate_hz = 50000.0;  ///< rate of the samples given to process()
  int flutes = 2;
  double commanded_rpm = 25000.0;
  double search_fraction = 0.15;  ///< search f within commanded·(1 ± this)
  double window_s = 0.0;         ///< analysis window; 0 = automatic (10 revolutions, 0.02–0.25 s)
  double hop_s = 0.0;            ///< time between windows; 0 = automatic (half a window)
  int max_harmonic = 0;          ///< highest harmonic used; 0 = automatic (4·flutes)
  double min_snr_db = 12.0;      ///< cutting when the harmonics stand this far above their floors
  double phase_gain = 0.5;       ///< fraction of each window's phase error corrected
  double lock_agreement = 0.01;  ///< windows a window apart agree in speed within this (relative)
  double lock_phase_rad = 0.8;   ///< ...and in tooth-harmonic phase within this
};

/// The fewest revolutions a tracker window may hold (validate()).
inline constexpr double kMinWindowRevolutions = 5.0;

/// The window and hop a configuration resolves to (automatic values filled in), in seconds.
struct TrackerTiming {
  double window_s = 0.0;
  double hop_s = 0.0;
};
TrackerTiming tracker_timing(const SpindleTrackerConfig& c);

/// @throws config::ConfigError naming the field.
SpindleTrackerConfig spindle_tracker_config_from_json(const nlohmann::json& j,
                                                      const std::string& path);
nlohmann::json to_json(const SpindleTrackerConfig& c);
/// @throws config::ConfigError naming the field for an inconsistent configuration.
void validate(const SpindleTrackerConfig& c, const std::string& path);

/// What is wrong with the window `c` resolves to, if it holds fewer than kMinWindowRevolutions
/// at its commanded speed (> 0), for the user: "value 0.05 s holds 4.16 revolutions at
/// `rpm_name` 5000: at least 5 needed (0.06 s or more)" (automatic: "automatic, 0.25 s,");
/// empty if nothing is.
[[nodiscard]] std::string window_problem(const SpindleTrackerConfig& c,
                                         const std::string& rpm_name);

struct SpindleEstimate {
  bool valid = false;     ///< locked: a current, consistent speed estimate
  bool cutting = false;   ///< periodic force: the strongest harmonic min_snr_db above the floor
  bool relocked = false;  ///< this update started a new lock (new angle reference)
  /// This window agrees with the one a window earlier (speed within lock_agreement, or on the
  /// line of a ramp through the two windows before; tooth phase within lock_phase_rad); false
  /// until a cutting stretch is two windows long.
  bool consistent = false;
  double spindle_hz = 0.0;  ///< this window's speed (meaningful when cutting)
  double spindle_rpm = 0.0;
  double uncertainty_rpm = 0.0;  ///< spread of the harmonics' speeds / √(harmonics used)
  double snr_db = 0.0;
  double agreement = 0.0;          ///< |f − f_earlier|/f against the window a window earlier
  double phase_error_rad = 0.0;    ///< tooth-harmonic phase against that window's
                                   ///< prediction, in radians of the tooth harmonic
  double angle_rad = 0.0;          ///< spindle angle at center_sample, [0, 2π)
  std::int64_t center_sample = 0;  ///< the window's centre, in input samples
  std::int64_t updates = 0;
  /// Windows that start unlocked (or lose the lock to a phase jump); 0 and false in the others:
  /// the strongest spectral line from half the slowest spindle frequency searched to the
  /// second tooth-passing harmonic of the fastest, and its SNR over the median of those bins.
  double line_hz = 0.0;
  double line_snr_db = 0.0;
  /// With z > 1 flutes: a line stands min_snr_db above the median at line_hz / z as well, the
  /// spindle line of a tooth-passing line_hz (runout makes one) — the likelier reading.
  bool line_has_spindle_line = false;
  /// The line is a spindle's: 6 dB more than min_snr_db above the median, with a line of its
  /// family min_snr_db above it too (at line_hz / z, 2·line_hz or z·line_hz) — not an isolated
  /// line of hum, a pump, a resonance or chatter.
  bool line_of_a_spindle = false;
  /// A spindle's line that no speed searched explains: none within commanded·(1 ±
  /// search_fraction) has it among its harmonics and a line of its own (at its frequency or
  /// its tooth-passing one). A spindle run off its commanded speed (an override) shows so.
  bool line_outside_search = false;
  /// Two windows agreed on a speed within the search that is an alias, not a lock: no line at
  /// its frequency nor its tooth-passing one, or a spindle's line that is none of its
  /// harmonics — the harmonics of a speed outside the search falling on some of its (40,000 rpm
  /// seen from 25,000 commanded as 26,667 with 2 flutes).
  bool alias_refused = false;
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
  /// The resolved window and hop (samples).
  [[nodiscard]] std::size_t window_samples() const { return window_; }
  [[nodiscard]] std::size_t hop_samples() const { return hop_; }
  /// The zero-padded spectrum's bin width (Hz).
  [[nodiscard]] double bin_hz() const {
    return config_.sample_rate_hz / static_cast<double>(fft_size_);
  }
  /// Samples taken since the last update (none before the first).
  [[nodiscard]] std::size_t samples_since_update() const {
    return estimate_.updates > 0 ? since_hop_ : 0;
  }
  /// Samples process() takes from now until the one that starts the next update (≥ 1): a
  /// caller can hand over that many at once and act on the update after the last.
  [[nodiscard]] std::size_t samples_to_update() const {
    const auto filled = static_cast<std::size_t>(next_sample_ - stream_start_);
    const std::size_t to_hop = since_hop_ < hop_ ? hop_ - since_hop_ : 0;
    const std::size_t to_window = filled < window_ ? window_ - filled : 0;
    return std::max<std::size_t>({to_hop, to_window, 1});
  }

 private:
  void update();
  double harmonic_score(double f_hz) const;
  struct Past;
  void remember(bool cutting, double hz, double tooth_phase_rad, std::int64_t center);
  [[nodiscard]] const Past* window_ago(std::int64_t center) const;
  [[nodiscard]] bool on_a_ramp(const Past& earlier, double hz, std::int64_t center) const;
  double magnitude_at(double f_hz) const;
  void find_strongest_line(SpindleEstimate& e);
  /// Whether a strongest line at line_hz is one a spindle at f_hz makes: one of its harmonics,
  /// within 1.5 bins.
  [[nodiscard]] bool line_fits(double line_hz, double f_hz) const;
  /// A spectral peak at bin k (a local maximum) off the bin, in bins.
  [[nodiscard]] double peak_offset_bins(std::size_t k) const;
  void release();

  SpindleTrackerConfig config_;
  std::size_t window_ = 0;
  std::size_t fft_size_ = 0;
  std::size_t hop_ = 0;
  int harmonics_ = 0;
  std::vector<double> ring_;  // the last window_ samples
  std::vector<double> hann_;
  std::vector<double> magnitude_;
  std::size_t magnitude_bins_ = 0;    // magnitude_'s bins update() computes (and reads)
  HarmonicFloors floors_;             // the harmonics' noise floors (update())
  std::vector<double> line_scratch_;  // find_strongest_line()'s median (2 × the bins)
  double* fft_in_ = nullptr;
  fftw_complex* fft_out_ = nullptr;
  fftw_plan plan_ = nullptr;

  std::int64_t next_sample_ = 0;
  std::size_t slot_ = 0;           // ring_ slot of the next sample: next_sample_ mod window_
  std::int64_t stream_start_ = 0;  // first sample since the last restart
  std::size_t since_hop_ = 0;
  SpindleEstimate estimate_;
  PhaseModel phase_;
  bool locked_ = false;
  // The last windows' estimates (a ring), so that each window can be compared with the one a
  // whole window earlier: windows that share samples agree whatever the signal.
  struct Past {
    bool cutting = false;
    double hz = 0.0;
    double tooth_phase_rad = 0.0;
    std::int64_t center = 0;
  };
  std::vector<Past> past_;  // sized at setup to hold a window's worth of hops
  int past_count_ = 0;
  std::array<double, 6> recent_hz_{};  // speeds of the last hops, for the ramp rate
  std::array<double, 6> recent_center_s_{};
  int recent_count_ = 0;
};

}  // namespace millwatch::signal
