#pragma once
// LCM logs of raw force blocks for tests, written the way lcm-logger records them.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <lcm/lcm-cpp.hpp>

#include "core/sim/scenario.hpp"
#include "millwatch/force_block_t.hpp"

namespace millwatch::test {

/// Appends `m` to `log` as an event of MILLWATCH_FORCE_RAW.
void write_force_event(lcm::LogFile& log, std::int64_t event, const force_block_t& m);

/// Simulates `s` and writes its blocks [first_block, end_block) of `block_samples` samples into a
/// new log at `path` (end_block < 0: to the end of the recording).
void write_force_log(const std::filesystem::path& path, const sim::Scenario& s,
                     std::size_t block_samples, std::int64_t first_block = 0,
                     std::int64_t end_block = -1);

}  // namespace millwatch::test
