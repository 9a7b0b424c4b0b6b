#pragma once
// `millwatch simulate SCENARIO.json -o CUT.csv`: writes a simulated dynamometer recording (CSV)
// and its JSON sidecar (CUT.json), then prints a summary.

#include <CLI/CLI.hpp>

namespace millwatch::shell {

/// Adds the subcommand to `app`.
void add_simulate_command(CLI::App& app);

}  // namespace millwatch::shell
