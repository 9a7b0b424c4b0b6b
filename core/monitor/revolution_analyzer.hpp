#pragma once
// One revolution's tooth events become a RevolutionRecord:
//   - the measured features on the sample ring (revolution_features.hpp);
//   - the revolution's own speed, from its period e_N − e_0 filtered over the last revolutions;
//   - its angle map: the straight line (least squares) through the events at their template
//     angles, event_rad[j] + 2π·turn, so that every sample has a spindle angle measured by the
//     revolution itself (a ramp cannot make it slip);
//   - the model revolution: the lockstep model's filtered force at each sample's angle, its
//     events sought near the measured ones and its features measured by the same detectors —
//     on the first 8 turns of a model and alignment (Lockstep::revision()), each once more at a
//     chosen sub-sample phase: the model is the same every turn, so then those 8 are summed up
//     (each figure the mean of its middle half) and kept, the events as angles placed on each
//     later turn by the turn's own angle map;
//   - the residual (measured − model) per axis, per flute window and per angle sector, and the
//     measured in-plane RMS √mean(Fx² + Fy²) for scale.
// Scratch for the model revolution is sized at construction; analyze() allocates nothing.

#include <array>
#include <cstdint>
#include <vector>

#include "core/monitor/lockstep.hpp"
#include "core/monitor/monitor_config.hpp"
#include "core/monitor/revolution_record.hpp"
#include "core/monitor/sample_ring.hpp"
#include "core/monitor/sync_average.hpp"
#include "core/monitor/tooth_events.hpp"

namespace millwatch::monitor {

/// Sample → tracker angle over one revolution: angle(n) = intercept + slope·n (rad).
struct AngleMap {
  double intercept_rad = 0.0;
  double slope_rad_per_sample = 0.0;
  [[nodiscard]] double at(double sample) const {
    return intercept_rad + slope_rad_per_sample * sample;
  }
  /// The sample at an angle (rad): at()'s inverse (slope > 0).
  [[nodiscard]] double sample_at(double angle_rad) const {
    return (angle_rad - intercept_rad) / slope_rad_per_sample;
  }
};

/// The least-squares line through the found events at their template angles (all events when
/// fewer than two were found).
AngleMap angle_map(const RevolutionEvents& events, const ToothEventTemplate& tmpl);

/// The revolution's speed from its tooth events (rpm): 60·f_s over the events' filtered period,
/// or 0 — not measured — when its closing CE1 event was not found.
double measured_rpm(const RevolutionEvents& e, const RevolutionMeasurement& m,
                    double sample_rate_hz);

class RevolutionAnalyzer {
 public:
  RevolutionAnalyzer() = default;
  /// @param max_revolution_samples longest revolution the model is evaluated over
  RevolutionAnalyzer(const MonitorConfig& config, std::size_t max_revolution_samples);

  /// Measures the revolution (ring channels 0-2 fx, fy, fz), and with an aligned `model` the
  /// model revolution and the residuals. `out.revolution`, `utime_us` and the window statistics
  /// are the caller's.
  void analyze(const RevolutionEvents& events, const ToothEventTemplate& tmpl,
               const SampleRing& ring, const Lockstep* model, RevolutionRecord& out);
  /// The model part of analyze() alone, on a revolution analyze() measured: the model
  /// revolution and the residuals when `model` is aligned (else out.model_valid false).
  void analyze_model(const RevolutionEvents& events, const ToothEventTemplate& tmpl,
                     const SampleRing& ring, const Lockstep& model, RevolutionRecord& out);

  /// Measure the model revolution once per model and alignment (true, the default) or anew
  /// on every turn.
  void keep_model_revolution(bool keep) {
    keep_ = keep;
    kept_ = KeptModelRevolution{};
  }

  /// Adds the revolution's samples to the synchronous average at their mapped angles and
  /// closes it as one revolution of the average.
  void add_to_average(const RevolutionEvents& events, const ToothEventTemplate& tmpl,
                      const SampleRing& ring, SyncAverage& sync) const;

 private:
  bool model_revolution(const RevolutionEvents& events, const ToothEventTemplate& tmpl,
                        const AngleMap& map, const Lockstep& model, RevolutionRecord& out);
  /// The model revolution from what was measured on it before (same model, same template):
  /// its events placed by this revolution's map, its rows computed over the measured windows.
  bool model_revolution_again(const RevolutionEvents& events, const AngleMap& map,
                              const Lockstep& model, RevolutionRecord& out);
  /// The model revolution on the rows of the model at the angles of samples s + shift (the
  /// turn's own: shift 0), its events and boundaries in the turn's samples.
  bool measure_model(const RevolutionEvents& measured, const ToothEventTemplate& tmpl,
                     const AngleMap& measured_map, const Lockstep& model, double shift,
                     RevolutionMeasurement& mm);
  /// Adds a model revolution to those measured for the kept one, which they make from
  /// kKeptTurns on.
  void remember_model_revolution(const RevolutionEvents& events, const AngleMap& map,
                                 const RevolutionMeasurement& mm);
  void residuals(const RevolutionMeasurement& m, const SampleRing& ring, const AngleMap& map,
                 RevolutionRecord& out) const;

  double sample_rate_hz_ = 0.0;
  double search_fraction_ = 0.3;
  int sectors_ = 0;
  /// The model's row at absolute sample s: first_ ≤ s ≤ the last row computed (the model
  /// revolution's margins when measured, the measured windows' last sample when kept).
  [[nodiscard]] const double* model_row(std::int64_t s) const {
    return &model_rows_[kModelRow * static_cast<std::size_t>(s - first_)];
  }

  // The model revolution from sample first_, a row per sample as the ring holds them: fx, fy,
  // fz and the squared in-plane force.
  static constexpr std::size_t kModelRow = 4;
  std::vector<double> model_rows_;
  std::int64_t first_ = 0;

  /// The model revolution of a model revision and an event template: each figure the mean of
  /// the middle half of its measurements on the first kKeptTurns turns, each at its own
  /// sub-sample phase (which moves the detectors' answer by a few tenths of a sample; now and
  /// then a search's start puts a valley a sample away), then placed on every later turn.
  static constexpr int kKeptTurns = 8;
  struct KeptModelRevolution {
    std::uint64_t revision = 0;  ///< Lockstep::revision(); 0: nothing kept
    ToothEventTemplate tmpl;     ///< whose flutes are the events' (ToothEventTracker::start)
    int turns = 0;               ///< turns measured; kept from kKeptTurns on
    /// Per turn measured: the events and boundaries as tracker angles within the turn (rad).
    std::array<std::array<double, kMaxFlutes + 1>, kKeptTurns> event_rad{};
    std::array<std::array<double, kMaxFlutes + 1>, kKeptTurns> boundary_rad{};
    std::array<RevolutionMeasurement, kKeptTurns> measured{};
    /// What is kept: the events and boundaries, and forces and ΔFy.
    std::array<double, kMaxFlutes + 1> kept_event_rad{};
    std::array<double, kMaxFlutes + 1> kept_boundary_rad{};
    RevolutionMeasurement kept;
    [[nodiscard]] bool holds(std::uint64_t r, const ToothEventTemplate& t) const {
      return revision == r && tmpl.kind == t.kind && tmpl.flutes == t.flutes &&
             tmpl.event_rad == t.event_rad && tmpl.boundary_rad == t.boundary_rad;
    }
    void keep();
  };
  KeptModelRevolution kept_;
  RevolutionMeasurement shifted_;  // scratch: the model revolution measured for the kept one
  bool keep_ = true;
};

}  // namespace millwatch::monitor
