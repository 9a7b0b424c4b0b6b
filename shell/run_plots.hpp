#pragma once
// `--plot DIR`: a run's pictures, drawn by gnuplot (Debian's gnuplot-nox, pngcairo) from the
// data files beside them (CSV, so that they can be re-plotted or read elsewhere):
//
//   speed.png          spindle speed over time: the tracker's windows and every revolution's own
//   alpha_delta_fy.png α and ΔFy per revolution
//   flute_peaks.png    each flute's peak in-plane force per revolution
//   sync_average.png   the last revolution-synchronous average, measured vs model, fx, fy, fz
//   spectrum.png       the recorded force's amplitude spectrum (Welch, Hann) with the
//                      tooth-passing harmonics marked
//
// A plot without data (no revolution measured, no model) is left out and said so in
// DIR/plots.txt.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "shell/run_recorder.hpp"

namespace millwatch::shell {

/// Writes the data files and the gnuplot script into `dir` and runs gnuplot on it. Returns the
/// PNG files written. @throws std::runtime_error if gnuplot is missing or fails (its messages
/// are in DIR/gnuplot.log).
std::vector<std::filesystem::path> write_plots(const RunRecorder& recorder,
                                               const nlohmann::json& summary,
                                               const std::filesystem::path& dir,
                                               const std::string& title);

}  // namespace millwatch::shell
