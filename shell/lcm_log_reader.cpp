#include "shell/lcm_log_reader.hpp"

#include <algorithm>
#include <array>
#include <stdexcept>

#include "msgs/force_block_check.hpp"
#include "msgs/lcm_convert.hpp"

namespace millwatch::shell {
namespace {

// lcm's event log format: each event is a 28-byte big-endian header (sync word 0xEDA1DA01,
// event number, timestamp µs, channel length, data length), the channel name, the data.
constexpr std::array<char, 4> kSync{'\xED', '\xA1', '\xDA', '\x01'};
constexpr std::int64_t kHeaderBytes = 28;
constexpr std::int32_t kMaxChannelBytes = 256;

std::uint64_t big_endian(const char* bytes, int n) {
  std::uint64_t v = 0;
  for (int i = 0; i < n; ++i) {
    v = (v << 8) | static_cast<unsigned char>(bytes[i]);
  }
  return v;
}

}  // namespace

LcmLogReader::LcmLogReader(const std::filesystem::path& path, std::string channel,
                           OnBadEvent on_bad_event, std::int64_t max_block_samples)
    : channel_(std::move(channel)),
      on_bad_event_(std::move(on_bad_event)),
      max_block_samples_(max_block_samples) {
  if (!std::filesystem::is_regular_file(path)) {
    throw std::runtime_error(path.string() + ": cannot read: no such file");
  }
  owned_ = std::make_unique<std::ifstream>(path, std::ios::binary);
  file_ = owned_.get();
  open(path.string());
}

LcmLogReader::LcmLogReader(std::istream& in, const std::string& name, std::string channel,
                           OnBadEvent on_bad_event, std::int64_t max_block_samples)
    : channel_(std::move(channel)),
      on_bad_event_(std::move(on_bad_event)),
      max_block_samples_(max_block_samples),
      file_(&in) {
  open(name);
}

void LcmLogReader::open(const std::string& name) {
  file_->seekg(0, std::ios::end);
  size_bytes_ = static_cast<std::int64_t>(file_->tellg());
  file_->seekg(0);
  std::array<char, 4> first{};
  if (!*file_ || size_bytes_ < 0 || !file_->read(first.data(), 4) || first != kSync) {
    throw std::runtime_error(name + ": cannot read as an LCM log (no event at byte 0)");
  }
}

std::optional<monitor::SampleBlock> LcmLogReader::next() {
  while (read_event()) {
    ++events_;
    if (const auto it = channel_events_.find(event_channel_); it != channel_events_.end()) {
      ++it->second;
    } else if (channel_events_.size() < kMaxChannelsTallied) {
      channel_events_.emplace(event_channel_, 1);
    } else {
      ++untallied_;
    }
    if (event_channel_ != channel_) {
      continue;
    }
    const messaging::ForceBlockCheck c =
        messaging::decode_force_block(data_.data(), data_.size(), max_block_samples_, message_);
    if (!c.ok()) {
      report(events_, "event on " + channel_ + " of " + std::to_string(data_.size()) +
                          " bytes does not decode as millwatch.force_block_t: " + c.describe());
      continue;
    }
    if (first_rate_hz_ == 0.0) {
      first_rate_hz_ = message_.sample_rate_hz;
    }
    return messaging::to_block(message_);
  }
  return std::nullopt;
}

bool LcmLogReader::read_event() {
  while (position_ + kHeaderBytes <= size_bytes_) {
    std::array<char, kHeaderBytes> header{};
    if (stream_at_ != position_) {  // not where the last event ended: after damage, or the first
      file_->clear();
      file_->seekg(position_);
    }
    stream_at_ = -1;  // until a whole event is read
    file_->read(header.data(), kHeaderBytes);
    const auto channel_bytes = static_cast<std::int32_t>(big_endian(header.data() + 20, 4));
    const auto data_bytes = static_cast<std::int32_t>(big_endian(header.data() + 24, 4));
    const std::int64_t end = position_ + kHeaderBytes + channel_bytes + data_bytes;
    const bool sound = std::equal(kSync.begin(), kSync.end(), header.begin()) &&
                       channel_bytes > 0 && channel_bytes <= kMaxChannelBytes && data_bytes >= 0 &&
                       end <= size_bytes_;
    if (sound) {
      event_channel_.resize(static_cast<std::size_t>(channel_bytes));
      data_.resize(static_cast<std::size_t>(data_bytes));
      file_->read(event_channel_.data(), channel_bytes);
      file_->read(reinterpret_cast<char*>(data_.data()), data_bytes);
      if (*file_) {
        position_ = stream_at_ = end;  // the next event is read on without a seek
        return true;
      }
    }
    if (!skip_damage()) {
      return false;
    }
  }
  if (position_ < size_bytes_) {
    report_truncated_end();
  }
  return false;
}

void LcmLogReader::report_truncated_end() {
  report(events_ + 1, "log ends inside an event (last " + std::to_string(size_bytes_ - position_) +
                          " bytes unreadable)");
  position_ = size_bytes_;
}

bool LcmLogReader::skip_damage() {
  const std::int64_t next = find_sync_word(position_ + 1);
  if (next < 0) {
    report_truncated_end();
    return false;
  }
  report(events_ + 1, "unreadable event at byte " + std::to_string(position_) + "; " +
                          std::to_string(next - position_) + " bytes skipped");
  position_ = next;
  return true;
}

std::int64_t LcmLogReader::find_sync_word(std::int64_t from_byte) {
  std::array<char, 65536> chunk{};
  std::int64_t chunk_start = from_byte;
  while (chunk_start < size_bytes_) {
    file_->clear();
    file_->seekg(chunk_start);
    file_->read(chunk.data(), chunk.size());
    const auto n = static_cast<std::size_t>(file_->gcount());
    if (n < kSync.size()) {
      return -1;
    }
    const char* hit = std::search(chunk.data(), chunk.data() + n, kSync.begin(), kSync.end());
    if (hit != chunk.data() + n) {
      return chunk_start + (hit - chunk.data());
    }
    // Step back so that a sync word split across two chunks is still found.
    chunk_start += static_cast<std::int64_t>(n - (kSync.size() - 1));
    if (n < chunk.size()) {
      return -1;
    }
  }
  return -1;
}

void LcmLogReader::report(std::int64_t event, const std::string& problem) {
  ++bad_events_;
  if (on_bad_event_) {
    on_bad_event_(event, problem);
  }
}

}  // namespace millwatch::shell
