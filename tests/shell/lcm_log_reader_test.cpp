// The LCM log reader on small logs, from a file and from memory: raw blocks of one channel in
// order, an empty block kept (it is not the end of the log), other channels skipped, malformed
// and oversized force_block_t events reported by event number and skipped before decoding.

#include "shell/lcm_log_reader.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <lcm/lcm-cpp.hpp>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "msgs/lcm_convert.hpp"
#include "tests/support/force_log.hpp"
#include "tests/support/test_paths.hpp"

namespace millwatch::shell {
namespace {

namespace fs = std::filesystem;

force_block_t block(std::int64_t seq, int n) {
  const std::vector<double> fx(static_cast<std::size_t>(n), static_cast<double>(seq));
  return messaging::to_message({seq * 1000, seq, 50000.0, fx, fx, fx});
}

/// Events: raw 10 samples; another channel; raw empty; raw 20; raw with num_samples −7; raw 30.
fs::path write_log(const fs::path& dir) {
  const fs::path path = dir / "small.lcmlog";
  lcm::LogFile log(path.string(), "w");
  test::write_force_event(log, 0, block(1, 10));
  std::vector<std::uint8_t> other = {1, 2, 3};
  lcm::LogEvent e{1, 0, "OTHER", 3, other.data()};
  log.writeEvent(&e);
  test::write_force_event(log, 2, block(2, 0));
  test::write_force_event(log, 3, block(3, 20));
  force_block_t negative = block(4, 2);
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(negative.getEncodedSize()));
  negative.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  bytes[32] = bytes[33] = bytes[34] = 0xFF;  // num_samples = −7
  bytes[35] = 0xF9;
  lcm::LogEvent bad{4, 0, "MILLWATCH_FORCE_RAW", static_cast<std::int32_t>(bytes.size()),
                    bytes.data()};
  log.writeEvent(&bad);
  test::write_force_event(log, 5, block(5, 30));
  return path;
}

struct Read {
  std::vector<std::pair<std::int64_t, std::size_t>> blocks;  // seq, samples
  std::vector<std::pair<std::int64_t, std::string>> bad;     // event, problem
};

void read_all(LcmLogReader& reader, Read& out) {
  while (const auto b = reader.next()) {
    out.blocks.emplace_back(b->seq, b->fx_N.size());
    EXPECT_EQ(b->fy_N.size(), b->fx_N.size());
    EXPECT_EQ(b->fz_N.size(), b->fx_N.size());
  }
  EXPECT_EQ(reader.bad_events(), static_cast<std::int64_t>(out.bad.size()));
}

TEST(LcmLogReader, ReadsRawBlocksKeepsEmptyOnesAndSkipsBadEvents) {
  const fs::path path = write_log(test::fresh_temp_dir());
  Read r;
  LcmLogReader reader(
      path, "MILLWATCH_FORCE_RAW",
      [&](std::int64_t event, const std::string& p) { r.bad.emplace_back(event, p); }, 25);
  read_all(reader, r);
  using B = std::pair<std::int64_t, std::size_t>;
  EXPECT_EQ(r.blocks, (std::vector<B>{{1, 10}, {2, 0}, {3, 20}}));
  ASSERT_EQ(r.bad.size(), 2u);
  EXPECT_EQ(r.bad[0].first, 5);
  EXPECT_EQ(r.bad[0].second,
            "event on MILLWATCH_FORCE_RAW of 84 bytes does not decode as millwatch.force_block_t: "
            "num_samples -7 is negative");
  EXPECT_EQ(r.bad[1].first, 6);
  EXPECT_EQ(r.bad[1].second,
            "event on MILLWATCH_FORCE_RAW of 756 bytes does not decode as millwatch.force_block_t: "
            "num_samples 30 is more than the maximum of 25");
  EXPECT_EQ(reader.events(), 6);
  EXPECT_EQ(reader.first_sample_rate_hz(), 50000.0);
}

TEST(LcmLogReader, ReadsTheSameFromMemory) {
  const fs::path path = write_log(test::fresh_temp_dir());
  std::ifstream file(path, std::ios::binary);
  const std::string bytes{std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
  std::istringstream in(bytes);
  Read r;
  LcmLogReader reader(in, "mem.lcmlog", "MILLWATCH_FORCE_RAW",
                      [&](std::int64_t e, const std::string& p) { r.bad.emplace_back(e, p); });
  read_all(reader, r);
  using B = std::pair<std::int64_t, std::size_t>;
  EXPECT_EQ(r.blocks, (std::vector<B>{{1, 10}, {2, 0}, {3, 20}, {5, 30}}));  // default maximum
  ASSERT_EQ(r.bad.size(), 1u);
  EXPECT_EQ(r.bad[0].first, 5);

  std::istringstream not_a_log("hello");
  try {
    LcmLogReader bad(not_a_log, "mem.lcmlog", "MILLWATCH_FORCE_RAW", nullptr);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "mem.lcmlog: cannot read as an LCM log (no event at byte 0)");
  }
}

}  // namespace
}  // namespace millwatch::shell
