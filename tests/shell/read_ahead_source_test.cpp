// Reading a recording ahead on a second thread gives what reading it in line gives, in the same
// order: blocks, bad records (each before the block it preceded), bad counts, progress, and an
// error where the reader throws it; stopping early does not wait for the rest of the file.

#include "shell/read_ahead_source.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include "tests/support/test_paths.hpp"

namespace millwatch::shell {
namespace {

/// A source of `blocks` blocks of varied sizes with bad records between some of them (and one
/// while opening) that throws at block `throw_at` (-1: never).
class ScriptedSource : public RecordingSource {
 public:
  ScriptedSource(OnBadRecord report, int blocks, int throw_at)
      : report_(std::move(report)), blocks_(blocks), throw_at_(throw_at) {
    description_ = "scripted";
    rate_hz_ = 50000.0;
    bad(-1, "while opening");
  }
  std::optional<monitor::SampleBlock> next(std::size_t max_samples) override {
    const int k = next_++;
    progress_ = static_cast<double>(k) / blocks_;
    if (k == throw_at_) {
      throw std::runtime_error("scripted.csv:" + std::to_string(k) + ": cannot read");
    }
    if (k % 3 == 0) {
      bad(k, "before block " + std::to_string(k));
    }
    if (k == blocks_) {
      bad(k, "at the end");
      return std::nullopt;
    }
    samples_.resize(static_cast<std::size_t>(k * 37) % max_samples + 1);
    std::iota(samples_.begin(), samples_.end(), 1000.0 * k);
    return monitor::SampleBlock{k * 1000, k, rate_hz_, samples_, samples_, samples_};
  }
  [[nodiscard]] std::int64_t bad_records() const override { return bad_; }
  [[nodiscard]] double progress() const override { return progress_; }
  [[nodiscard]] std::string what_it_held() const override {
    return std::to_string(blocks_) + " blocks in " + std::to_string(next_) + " calls";
  }

 private:
  void bad(std::int64_t where, const std::string& problem) {
    ++bad_;
    report_(where, problem);
  }
  OnBadRecord report_;
  int blocks_;
  int throw_at_;
  int next_ = 0;
  std::int64_t bad_ = 0;
  double progress_ = 0.0;
  std::vector<double> samples_;
};

/// Everything a reader of `source` sees, in order, up to the end, an error or `max_blocks`.
std::vector<std::string> drain(RecordingSource& source, std::vector<std::string>& log,
                               std::size_t max_samples, int max_blocks = 1 << 30) {
  try {
    for (int k = 0; k < max_blocks; ++k) {
      const auto b = source.next(max_samples);
      if (!b) {
        log.push_back("end, " + std::to_string(source.bad_records()) + " bad; " +
                      source.what_it_held());
        break;
      }
      const double sum = std::accumulate(b->fx_N.begin(), b->fx_N.end(), 0.0) +
                         std::accumulate(b->fy_N.begin(), b->fy_N.end(), 0.0) +
                         std::accumulate(b->fz_N.begin(), b->fz_N.end(), 0.0);
      log.push_back("block " + std::to_string(b->seq) + " at " + std::to_string(b->utime_us) +
                    ": " + std::to_string(b->fx_N.size()) + " samples, sum " + std::to_string(sum) +
                    "; " + std::to_string(source.bad_records()) + " bad, progress " +
                    std::to_string(source.progress()));
    }
  } catch (const std::runtime_error& e) {
    log.push_back(std::string("error: ") + e.what());
  }
  return log;
}

std::vector<std::string> in_line(int blocks, int throw_at, std::size_t max_samples) {
  std::vector<std::string> log;
  ScriptedSource source(
      [&](std::int64_t where, const std::string& p) {
        log.push_back("bad " + std::to_string(where) + ": " + p);
      },
      blocks, throw_at);
  return drain(source, log, max_samples);
}

std::vector<std::string> ahead(int blocks, int throw_at, std::size_t max_samples) {
  std::vector<std::string> log;
  const auto source = read_ahead(
      [&](OnBadRecord report) {
        return std::make_unique<ScriptedSource>(std::move(report), blocks, throw_at);
      },
      [&](std::int64_t where, const std::string& p) {
        log.push_back("bad " + std::to_string(where) + ": " + p);
      },
      max_samples);
  return drain(*source, log, max_samples);
}

TEST(ReadAheadSource, GivesTheSameBlocksAndReportsInTheSameOrder) {
  // 100 blocks: many times round the slots read ahead.
  const std::vector<std::string> expected = in_line(100, -1, 64);
  ASSERT_EQ(expected.size(), 1u + 34u + 100u + 1u + 1u);  // opening, every 3rd, blocks, end
  EXPECT_EQ(expected.front(), "bad -1: while opening");
  EXPECT_EQ(expected.back(), "end, 36 bad; 100 blocks in 101 calls");
  EXPECT_EQ(ahead(100, -1, 64), expected);
  EXPECT_EQ(ahead(0, -1, 1), in_line(0, -1, 1));
  EXPECT_EQ(ahead(30, -1, 40000), in_line(30, -1, 40000));  // large blocks: two slots
}

TEST(ReadAheadSource, AnErrorComesAfterTheBlocksBeforeIt) {
  const std::vector<std::string> expected = in_line(100, 40, 64);
  ASSERT_EQ(expected.back(), "error: scripted.csv:40: cannot read");
  EXPECT_EQ(ahead(100, 40, 64), expected);
  EXPECT_EQ(ahead(100, 0, 64), in_line(100, 0, 64));
}

TEST(ReadAheadSource, StopsEarlyAndRefusesAnotherBlockSize) {
  std::vector<std::string> log;
  {
    const auto source = read_ahead(
        [](OnBadRecord report) {
          return std::make_unique<ScriptedSource>(std::move(report), 1000000, -1);
        },
        [&](std::int64_t, const std::string&) {}, 64);
    drain(*source, log, 64, 5);
    EXPECT_THROW(source->next(65), std::invalid_argument);
  }  // the reading thread stops with the source
  ASSERT_EQ(log.size(), 5u);
  EXPECT_EQ(log[4].substr(0, 8), "block 4 ");
}

TEST(ReadAheadSource, ReadsAFileAsOpenRecordingDoes) {
  const auto dir = test::fresh_temp_dir();
  const auto path = dir / "cut.csv";
  {
    std::ofstream out(path);
    out << "t_s,fx_N,fy_N,fz_N\n";
    for (int i = 0; i < 5000; ++i) {
      if (i % 701 == 5) {
        out << i * 2e-5 << ",x,0,0\n";  // bad, and a gap
      } else {
        out << i * 2e-5 << "," << i << "," << -i << ",0.5\n";
      }
    }
  }
  auto run = [&](bool read_ahead_on) {
    std::vector<std::string> log;
    RecordingOptions o;
    o.on_bad = [&](std::int64_t where, const std::string& p) {
      log.push_back("bad " + std::to_string(where) + ": " + p);
    };
    const auto source =
        read_ahead_on ? open_recording_read_ahead(path, o, 100) : open_recording(path, o);
    EXPECT_EQ(source->format(), RecordingFormat::kMillwatchCsv);
    EXPECT_EQ(source->sample_rate_hz(), 50000.0);
    return drain(*source, log, 100);
  };
  const std::vector<std::string> expected = run(false);
  ASSERT_GT(expected.size(), 50u);
  EXPECT_EQ(expected[0].substr(0, 8), "bad 7: a");
  EXPECT_EQ(expected.back(), "end, 8 bad; 4992 rows read, 8 bad");
  EXPECT_EQ(run(true), expected);
}

}  // namespace
}  // namespace millwatch::shell
