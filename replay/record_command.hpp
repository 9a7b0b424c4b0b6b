#pragma once
// `millwatch record LOG [--url URL] [--channels REGEX]`: records LCM traffic into an LCM log
// (lcm-logger's format) without lcm-logger's limit of 30 queued messages, until SIGINT or
// SIGTERM (or --duration), then says what it recorded, channel by channel.

#include <string>

namespace millwatch::shell {

/// Its command-line options (replay/main.cpp).
struct RecordOptions {
  std::string output;
  std::string url = "udpm://239.255.76.67:7667?ttl=0";
  std::string channels = ".*";
  bool invert = false;
  bool force = false;
  double duration_s = 0.0;  // 0: until a signal
};

/// Runs the subcommand and returns its exit code; an error it throws, replay/main.cpp logs
/// and exits with 2.
int run_record(const RecordOptions& o);

}  // namespace millwatch::shell
