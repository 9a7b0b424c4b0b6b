#pragma once
// `millwatch replay CUT.csv|LOG.lcmlog`: the recorded cut through the monitoring pipeline, at
// real-time pace, k times it, or as fast as possible; optionally publishing on LCM; prints (and
// writes with --summary) the run's summary JSON.

#include <CLI/CLI.hpp>

namespace millwatch::shell {

void add_replay_command(CLI::App& app);

}  // namespace millwatch::shell
