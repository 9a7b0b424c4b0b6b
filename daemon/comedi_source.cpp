#include "daemon/comedi_source.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "daemon/scan_timing.hpp"

#ifdef MILLWATCH_HAVE_COMEDI
#include <comedilib.h>
#include <unistd.h>
#endif

namespace millwatch::daemon {

#ifdef MILLWATCH_HAVE_COMEDI

bool ComediSource::available() {
  return true;
}

ComediSource::ComediSource(const SourceConfig& config, double sample_rate_hz, BlockQueue& queue,
                           SourceCounters& counters)
    : config_(config), sample_rate_hz_(sample_rate_hz), queue_(queue), counters_(counters) {
  comedi_t* dev = comedi_open(config_.device.c_str());
  if (dev == nullptr) {
    throw std::runtime_error(config_.device +
                             ": cannot open Comedi device: " + comedi_strerror(comedi_errno()));
  }
  device_ = dev;
  subdevice_ = config_.subdevice >= 0 ? config_.subdevice
                                      : comedi_find_subdevice_by_type(dev, COMEDI_SUBD_AI, 0);
  if (subdevice_ < 0) {
    comedi_close(dev);
    throw std::runtime_error(config_.device + ": no analogue input subdevice");
  }
  long_samples_ =
      (comedi_get_subdevice_flags(dev, static_cast<unsigned>(subdevice_)) & SDF_LSAMPL) != 0;
  std::array<unsigned int, 3> chanlist{};
  for (std::size_t a = 0; a < 3; ++a) {
    auto& ch = config_.channels[a];
    const auto chan = static_cast<unsigned>(ch.daq_channel);
    // The range of the DAQ that holds the configured volts; its real limits and maxdata are
    // taken from the board.
    const int range = comedi_find_range(dev, static_cast<unsigned>(subdevice_), chan, UNIT_volt,
                                        ch.volts_min, ch.volts_max);
    if (range < 0) {
      comedi_close(dev);
      throw std::runtime_error(config_.device + ": channel " + std::to_string(chan) +
                               " has no range covering the configured volts");
    }
    const comedi_range* r = comedi_get_range(dev, static_cast<unsigned>(subdevice_), chan,
                                             static_cast<unsigned>(range));
    ch.volts_min = r->min;
    ch.volts_max = r->max;
    ch.maxdata = comedi_get_maxdata(dev, static_cast<unsigned>(subdevice_), chan);
    chanlist[a] = CR_PACK(chan, range, AREF_GROUND);
  }
  comedi_cmd cmd{};
  const std::uint32_t period_ns = scan_period_ns(sample_rate_hz_);
  if (comedi_get_cmd_generic_timed(dev, static_cast<unsigned>(subdevice_), &cmd, 3, period_ns) <
      0) {
    comedi_close(dev);
    throw std::runtime_error(config_.device + ": the board cannot acquire 3 channels at " +
                             std::to_string(sample_rate_hz_) + " Hz");
  }
  cmd.chanlist = chanlist.data();
  cmd.chanlist_len = 3;
  cmd.stop_src = TRIG_NONE;
  cmd.stop_arg = 0;
  for (int pass = 0; pass < 2; ++pass) {
    comedi_command_test(dev, &cmd);
  }
  // The period the board took (it rounds to its clock): a timed scan, or the conversions of a
  // scan that follows the last one.
  const std::uint64_t board_period_ns = cmd.scan_begin_src == TRIG_TIMER ? cmd.scan_begin_arg
                                        : cmd.convert_src == TRIG_TIMER
                                            ? std::uint64_t{cmd.convert_arg} * cmd.chanlist_len
                                            : 0;
  if (const std::string why = scan_rate_mismatch(sample_rate_hz_, board_period_ns); !why.empty()) {
    comedi_close(dev);
    throw std::runtime_error(config_.device + ": " + why);
  }
  if (comedi_command(dev, &cmd) < 0) {
    comedi_close(dev);
    throw std::runtime_error(config_.device +
                             ": cannot start acquisition: " + comedi_strerror(comedi_errno()));
  }
  thread_ = std::thread([this] { run(); });
}

ComediSource::~ComediSource() {
  stop_.store(true);
  if (thread_.joinable()) {
    thread_.join();
  }
  auto* dev = static_cast<comedi_t*>(device_);
  comedi_cancel(dev, static_cast<unsigned>(subdevice_));
  comedi_close(dev);
}

void ComediSource::run() {
  auto* dev = static_cast<comedi_t*>(device_);
  const int fd = comedi_fileno(dev);
  const std::size_t bytes_per_sample = long_samples_ ? sizeof(lsampl_t) : sizeof(sampl_t);
  const auto block = static_cast<std::size_t>(config_.block_samples);
  std::vector<unsigned char> buffer(block * 3 * bytes_per_sample);
  std::int64_t seq = 0;
  std::int64_t sample = 0;
  const std::int64_t start_us = std::chrono::duration_cast<std::chrono::microseconds>(
                                    std::chrono::system_clock::now().time_since_epoch())
                                    .count();
  std::size_t filled = 0;
  while (!stop_.load()) {
    const ssize_t got = read(fd, buffer.data() + filled, buffer.size() - filled);
    if (got <= 0) {
      spdlog::error("{}: acquisition stopped ({})", config_.device,
                    got == 0 ? "end of data" : comedi_strerror(comedi_errno()));
      counters_.ended.store(true);  // the daemon stops and says so (exit status 1)
      return;
    }
    filled += static_cast<std::size_t>(got);
    if (filled < buffer.size()) {
      continue;
    }
    filled = 0;
    const std::int64_t block_seq = seq++;
    const std::int64_t first = sample;
    sample += static_cast<std::int64_t>(block);
    BlockSlot* slot = queue_.claim();  // converted straight into the queue's free slot
    if (slot == nullptr) {
      ++counters_.queue_full;
      counters_.dropped(static_cast<std::int64_t>(block));
      continue;
    }
    slot->count = block;
    slot->seq = block_seq;
    slot->sample_rate_hz = sample_rate_hz_;
    slot->utime_us =
        start_us + static_cast<std::int64_t>(static_cast<double>(first) * 1e6 / sample_rate_hz_);
    for (std::size_t i = 0; i < block; ++i) {
      for (std::size_t a = 0; a < 3; ++a) {
        const std::size_t k = i * 3 + a;
        std::uint32_t code = 0;
        if (long_samples_) {
          code = reinterpret_cast<const lsampl_t*>(buffer.data())[k];
        } else {
          code = reinterpret_cast<const sampl_t*>(buffer.data())[k];
        }
        const auto s = config_.channels[a].scale(code);
        (a == 0 ? slot->fx : a == 1 ? slot->fy : slot->fz)[i] = s.force_N;
      }
    }
    slot->dropped_before = counters_.queuing_block();
    queue_.publish();
  }
}

#else

bool ComediSource::available() {
  return false;
}

ComediSource::ComediSource(const SourceConfig& config, double sample_rate_hz, BlockQueue& queue,
                           SourceCounters& counters)
    : config_(config), sample_rate_hz_(sample_rate_hz), queue_(queue), counters_(counters) {
  throw std::runtime_error(config.device +
                           ": this millwatchd was built without comedilib (install libcomedi-dev)");
}

ComediSource::~ComediSource() = default;

void ComediSource::run() {}

#endif

}  // namespace millwatch::daemon
