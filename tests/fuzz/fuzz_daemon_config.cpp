// libFuzzer: millwatchd's configuration file (shell::parse_json_text,
// daemon::daemon_config_from_json). A bad file may only be a ConfigError or a JSON syntax
// error; what reads must be usable: blocks that fit the queue's slots, a known log level.

#include <cstdint>
#include <stdexcept>
#include <string>

#include "core/config/json_reader.hpp"
#include "daemon/block_queue.hpp"
#include "daemon/daemon_config.hpp"
#include "fuzz_support.hpp"
#include "shell/json_file.hpp"

using namespace millwatch;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  nlohmann::json j;
  try {
    j = shell::parse_json_text(fuzz::text(data, size), "millwatchd.json");
  } catch (const std::runtime_error&) {
    return 0;
  }
  try {
    const daemon::DaemonConfig c = daemon::daemon_config_from_json(j);
    const auto slot = static_cast<int>(daemon::BlockSlot::kMaxSamples);
    MW_FUZZ_CHECK(c.source.block_samples >= 1 && c.source.block_samples <= slot);
    MW_FUZZ_CHECK(c.source.max_block_samples >= 1 && c.source.max_block_samples <= slot);
    MW_FUZZ_CHECK(spdlog::level::from_str(c.log_level) != spdlog::level::off);
    MW_FUZZ_CHECK(c.status_period_s > 0.0);
  } catch (const config::ConfigError&) {
  }
  return 0;
}

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::quiet();
  return 0;
}
