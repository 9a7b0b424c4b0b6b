// libFuzzer: a simulation scenario as millwatch simulate reads it (shell::parse_json_text,
// sim::scenario_from_json). A bad file may only be a ConfigError or a JSON syntax error; a
// scenario that reads must write back (to_json) to one that reads the same.

#include <cstdint>
#include <stdexcept>
#include <string>

#include "core/config/json_reader.hpp"
#include "core/sim/scenario.hpp"
#include "fuzz_support.hpp"
#include "shell/json_file.hpp"

using namespace millwatch;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  nlohmann::json j;
  try {
    j = shell::parse_json_text(fuzz::text(data, size), "scenario.json");
  } catch (const std::runtime_error&) {
    return 0;
  }
  sim::Scenario s;
  try {
    s = sim::scenario_from_json(j);
  } catch (const config::ConfigError&) {
    return 0;
  }
  const nlohmann::json written = sim::to_json(s);
  try {
    MW_FUZZ_CHECK(sim::to_json(sim::scenario_from_json(written)) == written);
  } catch (const config::ConfigError& e) {
    std::fprintf(stderr, "to_json gives what scenario_from_json refuses: %s\n%s\n", e.what(),
                 written.dump().c_str());
    std::abort();
  }
  return 0;
}

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::quiet();
  return 0;
}
