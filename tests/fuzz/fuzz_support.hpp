#pragma once
// What the libFuzzer targets share: an invariant check that fails the run (libFuzzer saves the
// input), the input as a string, the logs off, and the sample blocks a reader gives through the
// pipeline's first stage.

#include <spdlog/spdlog.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "core/monitor/input_check.hpp"

/// Aborts (a crash for libFuzzer) if `condition` does not hold.
#define MW_FUZZ_CHECK(condition)                                                             \
  do {                                                                                       \
    if (!(condition)) {                                                                      \
      std::fprintf(stderr, "%s:%d: invariant failed: %s\n", __FILE__, __LINE__, #condition); \
      std::abort();                                                                          \
    }                                                                                        \
  } while (false)

namespace millwatch::fuzz {

inline std::string text(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

/// Logs off: the readers warn about every bad input.
inline void quiet() {
  spdlog::set_level(spdlog::level::off);
}

/// A reader's block through InputCheck: whatever the reader let through must not break it, and
/// what it hands on must be as long as the block.
inline void check_block(monitor::InputCheck& check, const monitor::SampleBlock& block) {
  MW_FUZZ_CHECK(block.fy_N.size() == block.fx_N.size());
  MW_FUZZ_CHECK(block.fz_N.size() == block.fx_N.size());
  const monitor::CheckedBlock c = check.check(block);
  if (c.verdict == monitor::BlockVerdict::kAccepted) {
    MW_FUZZ_CHECK(c.fx_N.size() == block.fx_N.size());
    MW_FUZZ_CHECK(c.gap_samples >= 0);
    (void)check.utime_of(c.first_sample);
  } else {
    MW_FUZZ_CHECK(!c.problem.empty());
  }
}

}  // namespace millwatch::fuzz
