// libFuzzer: a recorded cut's CSV (shell::CsvCutReader, from memory) and its blocks through
// InputCheck. Every block the reader gives is non-empty, in time order, within the utime range.

#include <cstdint>
#include <sstream>
#include <stdexcept>

#include "fuzz_support.hpp"
#include "shell/csv_cut_reader.hpp"

using namespace millwatch;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(fuzz::text(data, size));
  std::int64_t bad_lines = 0;
  try {
    shell::CsvCutReader reader(in, "fuzz.csv", 50000.0,
                               [&](std::int64_t line, const std::string& problem) {
                                 MW_FUZZ_CHECK(line >= 2);
                                 MW_FUZZ_CHECK(!problem.empty());
                                 ++bad_lines;
                               });
    monitor::InputCheckConfig config;
    config.sample_rate_hz = 50000.0;
    config.max_block_samples = 64;
    monitor::InputCheck check(config);
    bool first = true;
    std::int64_t last_utime_us = 0;
    for (auto block = reader.next(64); !block.fx_N.empty(); block = reader.next(64)) {
      MW_FUZZ_CHECK(block.fx_N.size() <= 64);
      MW_FUZZ_CHECK(block.utime_us >= -monitor::kMaxAbsUtime_us &&
                    block.utime_us <= monitor::kMaxAbsUtime_us);
      MW_FUZZ_CHECK(first || block.utime_us >= last_utime_us);  // rows in time order
      first = false;
      last_utime_us = block.utime_us;
      fuzz::check_block(check, block);
    }
    MW_FUZZ_CHECK(reader.bad_lines() == bad_lines);
  } catch (const std::runtime_error&) {  // a wrong header: the run's error, not a crash
  }
  return 0;
}

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::quiet();
  return 0;
}
