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

#include <string>
#include <vector>

namespace millwatch::shell {

/// Its command-line options (replay/main.cpp).
struct CalibrateOptions {
  std::vector<std::string> inputs;
  std::string config;
  std::vector<double> feeds_um;
  std::string output;
  std::string columns;
  std::string name;
  bool tared = false;
  bool json = false;
  bool progress = true;
};

/// Runs the subcommand and returns its exit code; an error it throws, replay/main.cpp logs
/// and exits with 2.
int run_calibrate(const CalibrateOptions& o);

}  // namespace millwatch::shell
