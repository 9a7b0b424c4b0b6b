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

#include <CLI/CLI.hpp>

namespace millwatch::shell {

void add_diagnose_command(CLI::App& app);

}  // namespace millwatch::shell
