// libFuzzer: a recorded cut's CSV (shell::CsvCutReader, from memory) and its blocks through
// InputCheck. Every block the reader gives is non-empty, in time order, within the utime range;
// reading in pieces of a few bytes (every number, end-of-line and long line cut somewhere) gives
// the same blocks and the same bad lines as reading in one piece.

#include <cstdint>
#include <cstring>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "fuzz_support.hpp"
#include "shell/csv_cut_reader.hpp"

using namespace millwatch;

namespace {

struct Read {
  std::vector<std::pair<std::int64_t, std::string>> bad;
  std::vector<std::int64_t> utimes_us;
  std::vector<double> samples;  // fx, fy, fz of every block, bit for bit
  std::string error;            // a wrong header
};

Read read(const std::string& text, std::size_t buffer_bytes, bool check) {
  Read out;
  std::istringstream in(text);
  try {
    shell::CsvCutReader reader(
        in, "fuzz.csv", 50000.0,
        [&](std::int64_t line, const std::string& problem) {
          MW_FUZZ_CHECK(line >= 2);
          MW_FUZZ_CHECK(!problem.empty());
          out.bad.emplace_back(line, problem);
        },
        buffer_bytes);
    monitor::InputCheckConfig config;
    config.sample_rate_hz = 50000.0;
    config.max_block_samples = 64;
    monitor::InputCheck input_check(config);
    bool first = true;
    std::int64_t last_utime_us = 0;
    for (auto block = reader.next(64); !block.fx_N.empty(); block = reader.next(64)) {
      MW_FUZZ_CHECK(block.fx_N.size() <= 64);
      MW_FUZZ_CHECK(block.utime_us >= -monitor::kMaxAbsUtime_us &&
                    block.utime_us <= monitor::kMaxAbsUtime_us);
      MW_FUZZ_CHECK(first || block.utime_us >= last_utime_us);  // rows in time order
      first = false;
      last_utime_us = block.utime_us;
      out.utimes_us.push_back(block.utime_us);
      for (const auto channel : {block.fx_N, block.fy_N, block.fz_N}) {
        out.samples.insert(out.samples.end(), channel.begin(), channel.end());
      }
      if (check) {
        fuzz::check_block(input_check, block);
      }
    }
    MW_FUZZ_CHECK(reader.bad_lines() == static_cast<std::int64_t>(out.bad.size()));
  } catch (const std::runtime_error& e) {  // a wrong header: the run's error, not a crash
    out.error = e.what();
  }
  return out;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text = fuzz::text(data, size);
  const Read whole = read(text, shell::CsvCutReader::kDefaultBufferBytes, true);
  const Read pieces = read(text, 1 + size % 13, false);
  MW_FUZZ_CHECK(pieces.error == whole.error);
  MW_FUZZ_CHECK(pieces.bad == whole.bad);
  MW_FUZZ_CHECK(pieces.utimes_us == whole.utimes_us);
  MW_FUZZ_CHECK(pieces.samples.size() == whole.samples.size() &&
                (whole.samples.empty() ||
                 std::memcmp(pieces.samples.data(), whole.samples.data(),
                             whole.samples.size() * sizeof(double)) == 0));  // NaN too
  return 0;
}

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::quiet();
  return 0;
}
