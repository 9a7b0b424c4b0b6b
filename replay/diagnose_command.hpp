#pragma once
// `millwatch diagnose CUT --config C.json --report DIR`: where the model and the recorded cut
// disagree, which effect is missing, and the gap shrinking as it is added (millwatch issue 8;
// core/diagnose/diagnosis.hpp). Reads any recording the replay reads (its sidecar or --config
// describe the cut), starts from the plain model of the configured cut (--start configured: the
// configuration's own effects), writes DIR/report.md, report.html, report.json and the plots,
// prints the verdict and the steps; a progress line on a terminal.
//
// Several cuts (`millwatch diagnose CUT1 CUT2 … --report DIR`, one tool and material at
// different feeds, each feed from --feeds-um or the cut's sidecar): each cut diagnosed with its
// report in DIR/<stem>/, then compared across feeds (core/diagnose/across_feeds.hpp) in
// DIR/report.md, report.html, report.json and residual_vs_feed.png.

#include <string>
#include <vector>

namespace millwatch::shell {

/// Its command-line options (replay/main.cpp).
struct DiagnoseCliOptions {
  std::vector<std::string> inputs;
  std::string config;
  std::string sidecar;
  std::string report;
  std::string start = "plain";
  std::string candidates;
  std::vector<double> feeds_um;
  double band_hz = 0.0;
  double from_s = 0.0;
  double to_s = 0.0;
  int max_steps = 10;
  int exchanges = 3;
  int jobs = 0;  ///< candidates fitted at once (0: one per core)
  bool plots = true;
  bool progress = true;
};

/// Runs the subcommand and returns its exit code; an error it throws, replay/main.cpp logs
/// and exits with 2.
int run_diagnose(const DiagnoseCliOptions& o);

}  // namespace millwatch::shell
