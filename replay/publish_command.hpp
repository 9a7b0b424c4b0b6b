#pragma once
// `millwatch publish INPUT --url URL`: plays the DAQ bridge — publishes raw sample blocks
// (millwatch.force_block_t) on LCM from a recorded cut (CSV + sidecar) or a scenario simulated on
// the fly, paced at real time (or k times it, or as fast as possible).

#include <string>

namespace millwatch::shell {

/// Its command-line options (replay/main.cpp).
struct PublishOptions {
  std::string input;
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
