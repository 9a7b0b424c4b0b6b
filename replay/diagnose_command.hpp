#pragma once
// `millwatch diagnose CUT --config C.json --report DIR`: where the model and the recorded cut
// disagree, which effect is missing, and the gap shrinking as it is added (millwatch issue 8;
// core/diagnose/diagnosis.hpp). Reads any recording the replay reads (its sidecar or --config
// describe the cut), starts from the plain model of the configured cut (--start configured: the
// configuration's own effects), writes DIR/report.md, report.html, report.json and the plots,
// prints the verdict and the steps; a progress line on a terminal.

#include <CLI/CLI.hpp>

namespace millwatch::shell {

void add_diagnose_command(CLI::App& app);

}  // namespace millwatch::shell
