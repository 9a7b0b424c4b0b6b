#pragma once
// `millwatch publish INPUT --url URL`: plays the DAQ bridge — publishes raw sample blocks
// (millwatch.force_block_t) on LCM from a recorded cut (any format replay reads, described the
// same way: sidecar, --config, --columns) or a scenario (.json) simulated on the fly, paced at
// real time (or k times it, or as fast as possible). The blocks hold the recording's channels as
// read (the axis map is the monitor's to apply).

#include <string>

namespace millwatch::shell {

/// Its command-line options (replay/main.cpp).
struct PublishOptions {
  std::string input;
  std::string sidecar;  ///< as replay's: "" for CUT.json beside a recording
  std::string config;   ///< a monitor configuration (the rate of a text without a time column)
  std::string columns;  ///< as replay's
  std::string url = "udpm://239.255.76.67:7667?ttl=0";
  std::string channel = "MILLWATCH_FORCE_RAW";
  double speed = 1.0;
  int block_samples = 1000;
  double duration_s = 0.0;
  double start_utime_s = 0.0;
};

/// Runs the subcommand and returns its exit code; an error it throws, replay/main.cpp logs
/// and exits with 2.
int run_publish(const PublishOptions& o);

}  // namespace millwatch::shell
