#pragma once
// One revolution's tooth events become a RevolutionRecord:
//   - the measured features on the sample ring (revolution_features.hpp);
//   - the revolution's own speed, from its period e_N − e_0 filtered over the last revolutions;
//   - its angle map: the straight line (least squares) through the events at their template
//     angles, event_rad[j] + 2π·turn, so that every sample has a spindle angle measured by the
//     revolution itself (a ramp cannot make it slip);
//   - the model revolution: the lockstep model's filtered force at each sample's angle, its
//     events sought near the measured ones and its features measured by the same detectors —
//     once per model and alignment (Lockstep::revision()): the model is the same every turn, so
//     its events are kept as angles and placed on each later revolution by its own angle map,
//     its forces kept as they were measured;
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

  /// Measure the model revolution once per model and alignment (true, the default) or anew
  /// on every turn.
  void keep_model_revolution(bool keep) {
    keep_ = keep;
    kept_.revision = 0;
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
  void remember_model_revolution(const RevolutionEvents& events, const ToothEventTemplate& tmpl,
                                 const AngleMap& map, const Lockstep& model,
                                 const RevolutionMeasurement& mm);
  void residuals(const RevolutionMeasurement& m, const SampleRing& ring, const AngleMap& map,
                 RevolutionRecord& out) const;

  double sample_rate_hz_ = 0.0;
  double search_fraction_ = 0.3;
  int sectors_ = 0;
  /// The model's row at absolute sample s (first_ ≤ s).
  [[nodiscard]] const double* model_row(std::int64_t s) const {
    return &model_rows_[kModelRow * static_cast<std::size_t>(s - first_)];
  }

  // The model revolution from sample first_, a row per sample as the ring holds them: fx, fy,
  // fz and the squared in-plane force.
  static constexpr std::size_t kModelRow = 4;
  std::vector<double> model_rows_;
  std::int64_t first_ = 0;

  /// The model revolution as measured once for a model revision and an event template.
  struct KeptModelRevolution {
    std::uint64_t revision = 0;  ///< Lockstep::revision(); 0: nothing kept
    ToothEventKind kind = ToothEventKind::kValley;
    std::array<double, kMaxFlutes> template_rad{};
    /// The events and boundaries as tracker angles within their revolution's turn (rad).
    std::array<double, kMaxFlutes + 1> event_rad{};
    std::array<double, kMaxFlutes + 1> boundary_rad{};
    RevolutionMeasurement measured;  ///< its forces, α and ΔFy
  };
  KeptModelRevolution kept_;
  bool keep_ = true;
};

}  // namespace millwatch::monitor
