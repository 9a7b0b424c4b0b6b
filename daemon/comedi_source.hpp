#pragma once
// Live source (d): a Linux DAQ board through Comedi. Three analogue inputs (fx, fy, fz) are
// acquired by a timed command at the monitor's sample rate; raw codes become newtons through
// each channel's DAQ range and charge-amplifier setting (core/signal/daq_scaling.hpp), with DAQ
// clipping and amplifier overload flagged as saturation. Blocks are stamped with the host
// clock at the start plus the sample count, and go to the block queue like the LCM source's.
// Built only when comedilib is found (MILLWATCH_HAVE_COMEDI).

#include <atomic>
#include <string>
#include <thread>

#include "daemon/block_queue.hpp"
#include "daemon/daemon_config.hpp"
#include "daemon/source_counters.hpp"

namespace millwatch::daemon {

class ComediSource {
 public:
  /// Opens the device and starts acquiring. @throws std::runtime_error naming the device and
  /// what failed.
  ComediSource(const SourceConfig& config, double sample_rate_hz, BlockQueue& queue,
               SourceCounters& counters);
  ~ComediSource();
  ComediSource(const ComediSource&) = delete;
  ComediSource& operator=(const ComediSource&) = delete;

  /// Whether comedilib was available at build time.
  static bool available();

 private:
  void run();

  SourceConfig config_;
  double sample_rate_hz_;
  BlockQueue& queue_;
  SourceCounters& counters_;
  void* device_ = nullptr;  // comedi_t*
  int subdevice_ = 0;
  bool long_samples_ = false;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace millwatch::daemon
