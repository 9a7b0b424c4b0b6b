#pragma once
// Publishes the pipeline's outputs on LCM from a publisher thread.
//
// The pipeline calls this sink from the sample thread: each call copies a fixed-size value into
// a bounded lock-free queue and wakes the publisher — no allocation, no lock, no LCM call there.
// A full queue drops the value and counts it (pipeline_status5_t.messages_dropped). The publisher
// thread turns the values into LCM messages and publishes them, encoded into one buffer it
// reuses. It wakes at most every kPace: after a round it sleeps kPace and takes what came
// meanwhile, and only a publisher asleep with nothing to do is woken by the sample thread (a
// wake-up per output, ~1,300 a second at 333.3 kHz, cost more than the publishing). The
// lcm::LCM instance is passed in, not owned: tests hand a memq:// one, the daemon a udpm:// one.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <thread>
#include <variant>
#include <vector>

#include "core/monitor/pipeline.hpp"
#include "millwatch/sync_average2_t.hpp"
#include "msgs/spsc_queue.hpp"

namespace millwatch::messaging {

/// LCM channel names (upper case by LCM convention).
struct ChannelNames {
  std::string raw = "MILLWATCH_FORCE_RAW";
  std::string spindle = "MILLWATCH_SPINDLE";
  std::string tooth_periods = "MILLWATCH_TOOTH_PERIODS";
  std::string flute_peaks = "MILLWATCH_FLUTE_PEAKS";
  std::string residual = "MILLWATCH_RESIDUAL";
  std::string sync_average = "MILLWATCH_SYNC_AVERAGE";
  std::string runout = "MILLWATCH_RUNOUT";
  std::string coefficients = "MILLWATCH_COEFFICIENTS";
  std::string alert = "MILLWATCH_ALERT";
  std::string status = "MILLWATCH_STATUS";
};

/// A copy of the synchronous averages (measured and model) with a fixed size.
struct SyncSnapshot {
  static constexpr int kMaxBins = 4096;  // sync_average.bins' upper bound (monitor_config.cpp)
  std::int64_t utime_us = 0;
  std::int64_t revolution = 0;
  int window_revolutions = 0;
  int bins = 0;
  bool model_valid = false;
  std::array<std::array<double, kMaxBins>, 6> values{};  // fx, fy, fz, model fx, fy, fz
};

class LcmOutput : public monitor::PipelineSink {
 public:
  /// The longest a queued output waits for the publisher (in steady state; a backlog goes out
  /// in paced bursts).
  static constexpr std::chrono::microseconds kPace{5000};

  /// Starts the publisher thread. `downstream` (optional) also receives every output, in the
  /// sample thread (e.g. a summary or a log).
  LcmOutput(lcm::LCM& lcm, ChannelNames channels, monitor::PipelineSink* downstream = nullptr);
  ~LcmOutput() override;  ///< publishes what is queued, then stops the thread
  LcmOutput(const LcmOutput&) = delete;
  LcmOutput& operator=(const LcmOutput&) = delete;

  void on_revolution(const monitor::RevolutionRecord& r) override;
  void on_spindle(const monitor::SpindleUpdate& u) override;
  void on_sync_average(const monitor::SyncAverage& measured, const monitor::Lockstep* model,
                       std::int64_t revolution, std::int64_t utime_us) override;
  void on_alert(const monitor::Alert& a) override;
  void on_event(const monitor::PipelineEvent& e) override;
  /// Queues a pipeline_status5_t message.
  void publish_status(const monitor::PipelineStatus& s);

  /// Waits (up to `timeout_s`) until everything queued so far has been published.
  bool drain(double timeout_s = 5.0);
  /// Counts a message published on the same LCM outside the queue, from another thread
  /// (identification's estimates): in published() when LCM took it, else in dropped().
  void count_published_elsewhere(bool taken) { (taken ? published_ : dropped_).fetch_add(1); }
  [[nodiscard]] std::int64_t published() const { return published_.load(); }
  [[nodiscard]] std::int64_t dropped() const { return dropped_.load(); }

 private:
  using Item = std::variant<monitor::RevolutionRecord, monitor::SpindleUpdate, monitor::Alert,
                            monitor::PipelineStatus>;
  void enqueue(const Item& item);
  void wake_if_asleep();
  void run();
  void publish(const Item& item);
  /// Encodes `message` into buffer_ and publishes it on `channel`; false (counted as dropped)
  /// if it does not encode.
  template <class Message>
  bool send(const std::string& channel, const Message& message);

  lcm::LCM& lcm_;
  ChannelNames channels_;
  monitor::PipelineSink* downstream_;
  SpscQueue<Item, 1024> queue_;
  SpscQueue<SyncSnapshot, 8> sync_queue_;
  SyncSnapshot sync_scratch_;  // filled in the sample thread, then copied into the queue
  std::atomic<std::uint64_t> signal_{0};
  std::atomic<bool> asleep_{false};   // the publisher waits on signal_ with nothing to do
  std::vector<std::uint8_t> buffer_;  // the publisher's encode buffer
  sync_average2_t sync_message_;      // the publisher's; its arrays keep their capacity
  std::atomic<bool> stop_{false};
  std::atomic<std::int64_t> published_{0};
  std::atomic<std::int64_t> dropped_{0};
  std::atomic<std::int64_t> queued_{0};
  std::atomic<std::int64_t> handled_{0};
  std::int64_t alert_seq_ = 0;
  std::int64_t status_seq_ = 0;
  std::thread thread_;
};

}  // namespace millwatch::messaging
