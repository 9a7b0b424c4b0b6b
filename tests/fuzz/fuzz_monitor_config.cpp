// libFuzzer: a recorded cut's sidecar and a monitor configuration (--config), as millwatch
// replay reads them: JSON text (shell::parse_json_text), the sidecar's monitor configuration
// with the overrides merged over it (monitor_json_from_sidecar), monitor_config_from_json. The
// input is the sidecar, optionally followed by a NUL byte and the overrides. A bad file may
// only be a ConfigError (naming the field) or a JSON syntax error; a configuration that reads
// must write back (to_json) to one that reads the same.

#include <cstdint>
#include <stdexcept>
#include <string>

#include "core/config/json_reader.hpp"
#include "core/monitor/monitor_config.hpp"
#include "fuzz_support.hpp"
#include "shell/json_file.hpp"

using namespace millwatch;

namespace {

void read_back(const monitor::MonitorConfig& c) {
  const nlohmann::json j = monitor::to_json(c);
  monitor::MonitorConfig again;
  try {
    again = monitor::monitor_config_from_json(j);
  } catch (const config::ConfigError& e) {
    std::fprintf(stderr, "to_json gives what monitor_config_from_json refuses: %s\n%s\n", e.what(),
                 j.dump().c_str());
    std::abort();
  }
  MW_FUZZ_CHECK(monitor::to_json(again) == j);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string input = fuzz::text(data, size);
  const std::size_t nul = input.find('\0');
  nlohmann::json sidecar, overrides = nlohmann::json::object();
  try {
    sidecar = shell::parse_json_text(input.substr(0, nul), "sidecar.json");
    if (nul != std::string::npos) {
      overrides = shell::parse_json_text(input.substr(nul + 1), "config.json");
    }
  } catch (const std::runtime_error& e) {
    MW_FUZZ_CHECK(std::string(e.what()).find(".json: ") != std::string::npos);
    return 0;
  }
  try {  // as --config alone
    read_back(monitor::monitor_config_from_json(sidecar));
  } catch (const config::ConfigError&) {
  }
  try {  // as a sidecar with --config's overrides
    read_back(
        monitor::monitor_config_from_json(monitor::monitor_json_from_sidecar(sidecar, overrides)));
  } catch (const config::ConfigError&) {
  }
  return 0;
}

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::quiet();
  return 0;
}
