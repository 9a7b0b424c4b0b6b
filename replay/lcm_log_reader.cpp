#include "replay/lcm_log_reader.hpp"

#include <stdexcept>

#include "msgs/lcm_convert.hpp"

namespace millwatch::shell {

LcmLogReader::LcmLogReader(const std::filesystem::path& path, std::string channel,
                           std::function<void(std::int64_t, const std::string&)> on_bad_event)
    : path_(path), channel_(std::move(channel)), on_bad_event_(std::move(on_bad_event)) {
  if (!std::filesystem::is_regular_file(path)) {
    throw std::runtime_error(path.string() + ": cannot read: no such file");
  }
  log_ = std::make_unique<lcm::LogFile>(path.string(), "r");
  if (!log_->good()) {
    throw std::runtime_error(path.string() + ": cannot read as an LCM log");
  }
}

monitor::SampleBlock LcmLogReader::next() {
  while (const lcm::LogEvent* e = log_->readNextEvent()) {
    ++events_;
    if (e->channel != channel_) {
      continue;
    }
    const int used = message_.decode(e->data, 0, e->datalen);
    if (used < 0 || used != e->datalen) {
      ++bad_events_;
      if (on_bad_event_) {
        on_bad_event_(events_, "event on " + channel_ + " of " + std::to_string(e->datalen) +
                                   " bytes does not decode as millwatch.force_block_t");
      }
      continue;
    }
    if (first_rate_hz_ == 0.0) {
      first_rate_hz_ = message_.sample_rate_hz;
    }
    return messaging::to_block(message_);
  }
  return {};
}

}  // namespace millwatch::shell
