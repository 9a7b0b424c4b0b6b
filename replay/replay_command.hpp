#pragma once
// `millwatch replay CUT [CUT...]`: recorded cuts (millwatch CSV, DynoWare export, delimited text
// with a column map, MATLAB .mat, LCM log) through the monitoring pipeline.
//
// One cut: at real-time pace, k times it, or as fast as possible; optionally publishing on LCM;
// prints a readable summary (the JSON with --json), writes the summary JSON (--summary), one row
// per revolution (--revolutions, CSV or .jsonl) and plots (--plot DIR); a progress line on a
// terminal. Several cuts (or --table): each replayed by a child process, N at a time (-j), one
// row per cut in the table (--table cuts.csv) and on stdout.

#include <CLI/CLI.hpp>

namespace millwatch::shell {

void add_replay_command(CLI::App& app);

}  // namespace millwatch::shell
