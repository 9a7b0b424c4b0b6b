#pragma once
// `millwatch simulate SCENARIO.json -o CUT.csv`: writes a simulated dynamometer recording (CSV)
// and its JSON sidecar (CUT.json), then prints a summary.

#include <string>

namespace millwatch::shell {

/// Its command-line options (replay/main.cpp).
struct SimulateOptions {
  std::string scenario_path;
  std::string output_csv;
  double duration_s = 0.0;
  long long seed = -1;
  std::string truth_json;  ///< "": beside the CSV, CUT.truth.json
};

/// Runs the subcommand and returns its exit code; an error it throws, replay/main.cpp logs
/// and exits with 2.
int run_simulate(const SimulateOptions& o);

}  // namespace millwatch::shell
