// libFuzzer: an lcm-logger log (shell::LcmLogReader, from memory) and its raw blocks through
// InputCheck. Whatever the bytes, a block the reader gives has three channels of equal length
// within the maximum (force_block_t checked before it is decoded).

#include <cstdint>
#include <sstream>
#include <stdexcept>

#include "fuzz_support.hpp"
#include "shell/lcm_log_reader.hpp"

using namespace millwatch;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  constexpr std::int64_t kMax = 512;
  std::istringstream in(fuzz::text(data, size));
  try {
    std::int64_t bad = 0;
    shell::LcmLogReader reader(
        in, "fuzz.lcmlog", "MILLWATCH_FORCE_RAW",
        [&](std::int64_t event, const std::string& problem) {
          MW_FUZZ_CHECK(event >= 1);
          MW_FUZZ_CHECK(!problem.empty());
          ++bad;
        },
        kMax);
    monitor::InputCheckConfig config;
    config.sample_rate_hz = 50000.0;
    config.max_block_samples = kMax;
    monitor::InputCheck check(config);
    while (const auto block = reader.next()) {
      MW_FUZZ_CHECK(static_cast<std::int64_t>(block->fx_N.size()) <= kMax);
      fuzz::check_block(check, *block);
    }
    MW_FUZZ_CHECK(reader.bad_events() == bad);
  } catch (const std::runtime_error&) {  // not a log at all: the run's error, not a crash
  }
  return 0;
}

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::quiet();
  return 0;
}
