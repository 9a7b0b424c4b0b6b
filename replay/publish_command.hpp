#pragma once
// `millwatch publish INPUT --url URL`: plays the DAQ bridge — publishes raw sample blocks
// (millwatch.force_block_t) on LCM from a recorded cut (CSV + sidecar) or a scenario simulated on
// the fly, paced at real time (or k times it, or as fast as possible).

#include <CLI/CLI.hpp>

namespace millwatch::shell {

void add_publish_command(CLI::App& app);

}  // namespace millwatch::shell
