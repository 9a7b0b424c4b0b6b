#pragma once
// `millwatch replay CUT [CUT...]`: recorded cuts (millwatch CSV, DynoWare export, delimited text
// with a column map, MATLAB .mat, LCM log) through the monitoring pipeline.
//
// One cut: at real-time pace, k times it, or as fast as possible; optionally publishing on LCM;
// prints a readable summary (the JSON with --json), writes the summary JSON (--summary), one row
// per revolution (--revolutions, CSV or .jsonl) and plots (--plot DIR); a progress line on a
// terminal. Several cuts (or --table): each replayed by a child process, N at a time (-j), one
// row per cut in the table (--table cuts.csv) and on stdout.

#include <string>
#include <vector>

namespace millwatch::shell {

/// Its command-line options (replay/main.cpp).
struct ReplayOptions {
  std::vector<std::string> inputs;
  std::string sidecar;
  std::string config;
  std::string columns;
  std::string summary;
  /// Why the replay failed is written here too (a campaign's replays: its table says it).
  std::string error_file;
  std::string revolutions;
  std::string plot;
  std::string table;
  std::string publish_url;
  std::string raw_channel = "MILLWATCH_FORCE_RAW";
  double speed = 0.0;  // 0: as fast as possible
  int jobs = 1;
  bool json = false;
  bool realtime = false;
  bool publish_raw = false;
  bool zero_phase = false;
  bool progress = true;
  bool identify = true;
  int block_samples = 1000;
};

/// Runs the subcommand and returns its exit code; an error it throws, replay/main.cpp logs
/// and exits with 2.
int run_replay(const ReplayOptions& o);

}  // namespace millwatch::shell
