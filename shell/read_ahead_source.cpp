#include "shell/read_ahead_source.hpp"

#include <algorithm>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace millwatch::shell {
namespace {

class ReadAheadSource : public RecordingSource {
 public:
  ReadAheadSource(const std::function<std::unique_ptr<RecordingSource>(OnBadRecord)>& open,
                  OnBadRecord on_bad, std::size_t max_samples)
      : on_bad_(std::move(on_bad)), max_samples_(max_samples) {
    if (max_samples == 0) {
      throw std::invalid_argument("read_ahead: max_samples must be positive");
    }
    source_ = open([this](std::int64_t where, const std::string& problem) {
      if (filling_ == nullptr) {  // opening, before the thread starts: as it happens
        if (on_bad_) {
          on_bad_(where, problem);
        }
      } else {
        filling_->bad.emplace_back(where, problem);
      }
    });
    format_ = source_->format();
    description_ = source_->description();
    rate_hz_ = source_->sample_rate_hz();
    rate_stated_ = source_->rate_stated();
    bad_records_ = source_->bad_records();
    progress_ = source_->progress();
    // Each slot's buffers are allocated by the reading thread, the first time it fills them
    // (256 × 3 × 8 KB touched here took the caller ~3 ms); none after the first lap.
    slots_.resize(slot_count(max_samples));
    reader_ = std::thread([this] { read(); });
  }

  ~ReadAheadSource() override {
    {
      const std::lock_guard lock(mutex_);
      stop_ = true;
    }
    space_.notify_one();
    reader_.join();
  }
  ReadAheadSource(const ReadAheadSource&) = delete;
  ReadAheadSource& operator=(const ReadAheadSource&) = delete;

  std::optional<monitor::SampleBlock> next(std::size_t max_samples) override {
    if (max_samples != max_samples_) {
      throw std::invalid_argument("ReadAheadSource::next: blocks of " +
                                  std::to_string(max_samples) + " samples asked, " +
                                  std::to_string(max_samples_) + " read ahead");
    }
    if (ended_) {
      return std::nullopt;
    }
    std::unique_lock lock(mutex_);
    if (holding_) {  // the block returned last is done with: its slot can be read into
      holding_ = false;
      head_ = (head_ + 1) % slots_.size();
      --filled_;
      if (reader_waiting_ && filled_ <= slots_.size() / 2) {
        space_.notify_one();
      }
    }
    data_.wait(lock, [this] { return filled_ > 0; });
    Slot& s = slots_[head_];
    holding_ = true;
    lock.unlock();
    for (const auto& [where, problem] : s.bad) {
      if (on_bad_) {
        on_bad_(where, problem);
      }
    }
    bad_records_ = s.bad_records;
    progress_ = s.progress;
    if (s.error) {
      ended_ = true;
      std::rethrow_exception(s.error);
    }
    if (s.end) {
      ended_ = true;
      held_ = s.held;
      end_note_ = s.end_note;
      return std::nullopt;
    }
    monitor::SampleBlock b;
    b.utime_us = s.utime_us;
    b.seq = s.seq;
    b.sample_rate_hz = s.sample_rate_hz;
    b.fx_N = s.fx;
    b.fy_N = s.fy;
    b.fz_N = s.fz;
    return b;
  }
  [[nodiscard]] std::int64_t bad_records() const override { return bad_records_; }
  [[nodiscard]] double progress() const override { return progress_; }
  [[nodiscard]] std::string what_it_held() const override { return held_; }
  [[nodiscard]] std::string end_note() const override { return end_note_; }

 private:
  /// A block read ahead, with what the reader reported while reading it.
  struct Slot {
    std::vector<double> fx, fy, fz;
    std::int64_t utime_us = 0;
    std::int64_t seq = 0;
    double sample_rate_hz = 0.0;
    std::vector<std::pair<std::int64_t, std::string>> bad;  // where, problem
    std::int64_t bad_records = 0;
    double progress = 0.0;
    bool end = false;      // no block: the recording ends here
    std::string held;      // at the end: the source's what_it_held()
    std::string end_note;  // and its end_note()
    std::exception_ptr error;
  };
  /// Up to 256 blocks ahead, and at most ~256 Ki samples (6 MiB; --block 65536: four blocks):
  /// enough for the reader to keep parsing while the pipeline builds its model (~10 ms; the
  /// 10 s 50 kHz CSV parses at ~15 blocks of 1,000 samples a millisecond).
  static std::size_t slot_count(std::size_t max_samples) {
    return std::clamp<std::size_t>(std::size_t{262144} / max_samples, 2, 256);
  }

  /// The reading thread: fills the free slots in order until the recording ends or fails.
  void read() {
    while (true) {
      std::unique_lock lock(mutex_);
      // Once the slots are full, wait for half of them to be free: one wake-up per half.
      if (filled_ == slots_.size()) {
        reader_waiting_ = true;
        space_.wait(lock, [this] { return stop_ || filled_ <= slots_.size() / 2; });
        reader_waiting_ = false;
      }
      if (stop_) {
        return;
      }
      Slot& s = slots_[(head_ + filled_) % slots_.size()];
      lock.unlock();
      s.bad.clear();
      s.end = false;
      s.error = nullptr;
      filling_ = &s;
      try {
        if (const std::optional<monitor::SampleBlock> b = source_->next(max_samples_)) {
          s.fx.reserve(max_samples_);  // the first lap only
          s.fy.reserve(max_samples_);
          s.fz.reserve(max_samples_);
          s.fx.assign(b->fx_N.begin(), b->fx_N.end());
          s.fy.assign(b->fy_N.begin(), b->fy_N.end());
          s.fz.assign(b->fz_N.begin(), b->fz_N.end());
          s.utime_us = b->utime_us;
          s.seq = b->seq;
          s.sample_rate_hz = b->sample_rate_hz;
        } else {
          s.end = true;
          s.held = source_->what_it_held();
          s.end_note = source_->end_note();
        }
      } catch (...) {
        s.error = std::current_exception();
      }
      s.bad_records = source_->bad_records();
      s.progress = source_->progress();
      const bool last = s.end || s.error;
      lock.lock();
      ++filled_;
      lock.unlock();
      data_.notify_one();
      if (last) {
        return;
      }
    }
  }

  OnBadRecord on_bad_;
  std::size_t max_samples_;
  std::unique_ptr<RecordingSource> source_;  // used by the reading thread once it runs
  std::vector<Slot> slots_;
  Slot* filling_ = nullptr;  // the slot being read into (reading thread)
  // The caller's side.
  bool holding_ = false;  // slots_[head_] holds the block next() returned last
  bool ended_ = false;
  std::int64_t bad_records_ = 0;
  double progress_ = 0.0;
  std::string held_;      // the source's what_it_held(), once it ended
  std::string end_note_;  // and its end_note()
  // Shared, under mutex_: slots [head_, head_ + filled_) are read (the first one held while
  // holding_), the rest free.
  std::mutex mutex_;
  std::condition_variable data_;   // a slot was read
  std::condition_variable space_;  // slots were freed, or stop_
  std::size_t head_ = 0;
  std::size_t filled_ = 0;
  bool reader_waiting_ = false;
  bool stop_ = false;
  std::thread reader_;  // last: started once everything above is built
};

}  // namespace

std::unique_ptr<RecordingSource> read_ahead(
    const std::function<std::unique_ptr<RecordingSource>(OnBadRecord)>& open, OnBadRecord on_bad,
    std::size_t max_samples) {
  return std::make_unique<ReadAheadSource>(open, std::move(on_bad), max_samples);
}

std::unique_ptr<RecordingSource> open_recording_read_ahead(const std::filesystem::path& path,
                                                           const RecordingOptions& options,
                                                           std::size_t max_samples) {
  return read_ahead(
      [&](OnBadRecord report) {
        RecordingOptions o = options;
        o.on_bad = std::move(report);
        return open_recording(path, o);
      },
      options.on_bad, max_samples);
}

}  // namespace millwatch::shell
