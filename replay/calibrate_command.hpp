#pragma once
// `millwatch calibrate CUT1 CUT2 … [--config C.json] [--feeds-um f1,f2,…] [-o material.json]`:
// one set of force-law coefficients and one runout fitted across a feed sweep made with one tool
// in one clamping (identify::calibrate), with the classic average-force regression beside it; a
// material preset the replay and the daemon accept (shell/material_preset.hpp).
//
// Each cut is described as the replay describes it (its sidecar beside it under --config's
// overrides, or --config alone); its feed per tooth comes from --feeds-um (one per cut, in
// order) or from its sidecar, and the two must agree where both are given. Each recording runs
// through the monitor (lockstep off) and its synchronous-average windows are kept.

#include <CLI/CLI.hpp>

namespace millwatch::shell {

void add_calibrate_command(CLI::App& app);

}  // namespace millwatch::shell
