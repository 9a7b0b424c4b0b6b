#pragma once
// Reads the raw force blocks of an LCM log (as lcm-logger writes it) from one channel.
// Events of other channels are skipped; an event that is not a whole force_block_t of at most
// max_block_samples samples (msgs/force_block_check.hpp: checked before it is decoded) is
// reported and skipped; a damaged event is reported and reading resumes at the next sync word,
// so damage costs only the events it touches (lcm 1.3.1's own reader also drops the sound event
// before a broken sync word, and stops at a broken length); a log cut short ends at its last
// whole event, with a warning.

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <istream>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/monitor/sample_block.hpp"
#include "millwatch/force_block_t.hpp"

namespace millwatch::shell {

class LcmLogReader {
 public:
  /// Called for each bad event with its number (1-based, counting every channel's events) and
  /// what is wrong with it.
  using OnBadEvent = std::function<void(std::int64_t event, const std::string& problem)>;
  /// The most samples a block may have unless told otherwise (the pipeline's own limit).
  static constexpr std::int64_t kDefaultMaxBlockSamples = 65536;

  /// Reads the log at `path`. @throws std::runtime_error "PATH: cannot read as an LCM log".
  LcmLogReader(const std::filesystem::path& path, std::string channel, OnBadEvent on_bad_event,
               std::int64_t max_block_samples = kDefaultMaxBlockSamples);
  /// Reads `in` (seekable; it must outlive the reader), named `name` in errors.
  LcmLogReader(std::istream& in, const std::string& name, std::string channel,
               OnBadEvent on_bad_event, std::int64_t max_block_samples = kDefaultMaxBlockSamples);

  /// The next raw block (views valid until the next call), possibly empty if the log holds an
  /// empty one; nothing at the end of the log.
  std::optional<monitor::SampleBlock> next();
  [[nodiscard]] std::int64_t events() const { return events_; }
  [[nodiscard]] std::int64_t bad_events() const { return bad_events_; }
  /// Fraction of the log's bytes read so far.
  [[nodiscard]] double progress() const {
    return size_bytes_ > 0 ? static_cast<double>(position_) / static_cast<double>(size_bytes_)
                           : 1.0;
  }
  /// The events read so far on each channel (this reader's and the others', at most
  /// kMaxChannelsTallied names; events on names past them are not tallied): what a log that
  /// gave no block holds.
  [[nodiscard]] const std::map<std::string, std::int64_t>& channel_events() const {
    return channel_events_;
  }
  static constexpr std::size_t kMaxChannelsTallied = 32;
  /// Events on channels past the kMaxChannelsTallied named.
  [[nodiscard]] std::int64_t events_untallied() const { return untallied_; }
  /// Sample rate of the first block (0 before it).
  [[nodiscard]] double first_sample_rate_hz() const { return first_rate_hz_; }

 private:
  /// Reads the event at position_ into event_channel_ and data_; false at the end of the log.
  bool read_event();
  /// Reports the damaged event at position_ and moves to the next sync word; false if none.
  bool skip_damage();
  /// Byte offset of the next event sync word at or after from_byte, or -1.
  std::int64_t find_sync_word(std::int64_t from_byte);
  /// Reports the unreadable rest of the log from position_ and moves to its end.
  void report_truncated_end();
  void report(std::int64_t event, const std::string& problem);

  void open(const std::string& name);

  std::string channel_;
  OnBadEvent on_bad_event_;
  std::int64_t max_block_samples_;
  std::unique_ptr<std::ifstream> owned_;  // when reading a path
  std::istream* file_ = nullptr;
  std::int64_t size_bytes_ = 0;
  std::int64_t position_ = 0;  ///< byte offset of the next event
  /// Where the stream is if known (after a whole event), else -1: events read in sequence need
  /// no seek, which would drop the stream's buffer.
  std::int64_t stream_at_ = -1;
  std::string event_channel_;
  std::vector<std::uint8_t> data_;
  force_block_t message_;
  std::int64_t events_ = 0;
  std::int64_t bad_events_ = 0;
  std::map<std::string, std::int64_t> channel_events_;
  std::int64_t untallied_ = 0;
  double first_rate_hz_ = 0.0;
};

}  // namespace millwatch::shell
