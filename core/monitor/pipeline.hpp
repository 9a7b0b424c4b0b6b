#pragma once
// The monitoring pipeline: dynamometer samples in, per-revolution features, residuals against
// the model in lockstep, spindle state and alerts out. The live daemon and the replay build the
// same pipeline from the same MonitorConfig; only the source and the pacing differ. Everything
// is driven by sample time (the blocks' utime), so a replay of a recorded stream reproduces the
// live results exactly.
//
//   InputCheck → AxisMap → LowPass (3 axes) → tare → |Fxy|² ─┬→ SpindleTracker (decimated)
//                                                             ├→ SyncAverage (tracked angle)
//                                                             └→ SampleRing ← Lockstep samples
// The tare re-zeroes the channels while the tracker sees no cutting (charge-amplifier drift).
//   SampleRing → RevolutionMeter (measured) + RevolutionMeter (model) → RevolutionRecord
//   RevolutionRecord, input counters → AlertEngine
//
// Outputs go to a PipelineSink, called from the thread that calls process(). After set-up the
// steady state allocates nothing, except when a new lock (re)builds the lockstep model.

#include <array>
#include <cstdint>
#include <memory>
#include <string_view>
#include <vector>

#include "core/monitor/alert_engine.hpp"
#include "core/monitor/input_check.hpp"
#include "core/monitor/lockstep.hpp"
#include "core/monitor/monitor_config.hpp"
#include "core/monitor/revolution_meter.hpp"
#include "core/monitor/revolution_record.hpp"
#include "core/monitor/sample_block.hpp"
#include "core/monitor/sample_ring.hpp"
#include "core/monitor/sync_average.hpp"
#include "core/signal/butterworth_lowpass.hpp"
#include "core/signal/spindle_tracker.hpp"
#include "core/signal/zero_phase_filter.hpp"

namespace millwatch::monitor {

struct SpindleUpdate {
  std::int64_t utime_us = 0;  ///< time of the estimate's window centre
  std::int64_t seq = 0;
  std::int64_t revolution = 0;  ///< tracked turns since the stream began
  signal::SpindleEstimate estimate;
  double commanded_rpm = 0.0;
};

enum class PipelineEventKind {
  kBlockRejected,  ///< detail: why; count: samples dropped
  kGap,            ///< count: samples missing
  kNonFinite,      ///< count: samples replaced in the block
  kSaturated,      ///< count: samples at the range in the block
  kLockAcquired,   ///< value: spindle rpm
  kLockLost,
  kModelAligned,    ///< value: alignment correlation
  kModelBuilt,      ///< value: spindle rpm of the model
  kCuttingStopped,  ///< value: the revolution's peak force, N
  kCuttingResumed   ///< value: the revolution's peak force, N
};

std::string_view to_string(PipelineEventKind kind);

struct PipelineEvent {
  PipelineEventKind kind = PipelineEventKind::kGap;
  std::int64_t utime_us = 0;
  std::int64_t sample = 0;
  std::int64_t block_seq = 0;
  std::int64_t count = 0;
  double value = 0.0;
  std::string_view detail;
};

struct PipelineStatus {
  InputCounters input;
  std::int64_t revolutions = 0;
  std::int64_t valid_revolutions = 0;
  std::int64_t idle_revolutions = 0;  ///< measured without a cutting force (not reported)
  std::int64_t utime_us = 0;          ///< newest sample
  double spindle_rpm = 0.0;
  bool cutting = false;
  std::string_view state = "acquiring";
};

/// Receives the pipeline's outputs (default: ignore).
class PipelineSink {
 public:
  virtual ~PipelineSink() = default;
  virtual void on_revolution(const RevolutionRecord& /*record*/) {}
  virtual void on_spindle(const SpindleUpdate& /*update*/) {}
  /// Every sync-average window of revolutions: the measured average and the model (may be null).
  virtual void on_sync_average(const SyncAverage& /*measured*/, const Lockstep* /*model*/,
                               std::int64_t /*revolution*/, std::int64_t /*utime_us*/) {}
  virtual void on_alert(const Alert& /*alert*/) {}
  virtual void on_event(const PipelineEvent& /*event*/) {}
};

class Pipeline {
 public:
  /// @throws config::ConfigError for an inconsistent configuration.
  Pipeline(const MonitorConfig& config, PipelineSink& sink);

  /// Processes one block from any source.
  void process(const SampleBlock& block);
  /// End of the record: with zero-phase filtering, processes the samples still held for the
  /// backward pass (nothing to do for the causal filter).
  void finish();

  [[nodiscard]] PipelineStatus status() const;
  [[nodiscard]] const MonitorConfig& config() const { return config_; }
  /// The tracker's phase model at full rate (valid while locked).
  [[nodiscard]] const signal::PhaseModel& phase() const { return phase_; }
  [[nodiscard]] const Lockstep& lockstep() const { return lockstep_; }
  [[nodiscard]] const signal::ButterworthDesign& filter() const { return filter_; }

 private:
  void restart_stream(std::int64_t first_sample);
  void bridge_gap(std::int64_t first_sample);
  /// Everything after the low-pass filter, for sample n.
  void downstream(std::int64_t n, double fx, double fy, double fz);
  /// Zero-phase mode: processes the filter's ready samples (all held ones when flushing).
  void drain_zero_phase(std::size_t ready);
  void on_tracker_update();
  void start_measuring(std::int64_t sample);
  void track_offsets(const RevolutionMeasurement& m, int channel,
                     std::array<double, 2>& offset_N) const;
  void measure_revolutions();
  void emit_record(const RevolutionMeasurement& measured, const RevolutionMeasurement* model);
  void fill_residuals(RevolutionRecord& r) const;
  void check_input_health(std::int64_t utime_us);
  void event(PipelineEventKind kind, std::int64_t sample, std::int64_t count, double value,
             std::string_view detail, std::int64_t block_seq = 0);

  MonitorConfig config_;
  PipelineSink& sink_;
  InputCheck input_;
  signal::ButterworthDesign filter_;
  std::array<signal::LowPassFilter, 3> lowpass_;
  signal::ZeroPhaseFilter zero_phase_;       // instead of lowpass_ when configured
  std::int64_t zero_phase_next_sample_ = 0;  // sample number of its next output
  signal::SpindleTracker tracker_;
  int decimation_ = 1;
  signal::PhaseModel phase_;  // full rate
  SyncAverage sync_;
  SampleRing ring_;
  Lockstep lockstep_;
  RevolutionMeter measured_meter_;
  RevolutionMeter model_meter_;
  AlertEngine alerts_;

  std::int64_t stream_start_ = 0;
  bool stream_fresh_ = true;  // the next sample starts a stretch: settle the filters
  double last_turn_ = 0.0;    // floor(angle/2π) of the previous sample
  bool measuring_ = false;
  std::int64_t revolutions_ = 0;
  std::int64_t valid_revolutions_ = 0;
  std::int64_t idle_revolutions_ = 0;
  double typical_peak_N_ = 0.0;  // running level of the revolutions' peak force
  bool idle_ = false;            // the last revolution had no cutting force
  std::int64_t spindle_seq_ = 0;
  std::int64_t sync_revolutions_since_report_ = 0;
  std::int64_t next_health_check_ = 0;
  double tooth_delay_s_ = 0.0;
  std::array<double, 3> tare_N_{};  // channel zero, re-established while not cutting
  double tare_gain_ = 0.0;
  double envelope_sq_ = 0.0;  // decaying peak of the squared in-plane force, N²
  double envelope_decay_ = 0.0;
  double last_detect_ = -1.0;
  std::int64_t max_bridged_gap_ = 0;
  double last_rpm_ = 0.0;
  double last_hop_hz_ = 0.0;
  bool settled_ = false;  // the speed estimate has held still since the lock

  /// A small FIFO of revolutions waiting for their partner (the oldest is dropped when full).
  struct PendingRevolutions {
    static constexpr std::size_t kCapacity = 64;
    std::array<RevolutionMeasurement, kCapacity> items{};
    std::size_t head = 0;
    std::size_t count = 0;
    [[nodiscard]] bool empty() const { return count == 0; }
    [[nodiscard]] std::size_t size() const { return count; }
    [[nodiscard]] const RevolutionMeasurement& front() const { return items[head]; }
    void pop() {
      head = (head + 1) % kCapacity;
      --count;
    }
    void push(const RevolutionMeasurement& m) {
      if (count == kCapacity) {
        pop();
      }
      items[(head + count) % kCapacity] = m;
      ++count;
    }
    void clear() { head = count = 0; }
  };
  PendingRevolutions pending_measured_;  // pairing of measured and model revolutions
  PendingRevolutions pending_model_;

  // α and ΔFy over the last window of valid revolutions.
  std::vector<double> alpha_window_, dfy_window_;
  int window_count_ = 0;
  int window_next_ = 0;
};

}  // namespace millwatch::monitor
