#pragma once
// `millwatch diagnose --report DIR`: the diagnosis for people and machines.
//
//   report.json          core/diagnose/diagnosis_json.hpp
//   report.md, .html     a table per step (effect added, its parameters ± σ, residual RMS per
//                        axis in N and in % of the measured RMS, the criterion and its gain, the
//                        runner-up and the margin), every candidate scored, the localisation, the
//                        plots
//   revolution_S.png     stage S (0: the starting model, then one per effect added): measured vs
//                        model over one revolution (synchronous average), fx and fy
//   spectrum_S.png       stage S: the residual's amplitude spectrum over the band, with the
//                        noise floor's level
//   *.csv, plots.gp      the plots' data and gnuplot script (Debian's gnuplot-nox, pngcairo)

#include <filesystem>
#include <string>
#include <vector>

#include "core/diagnose/diagnosis.hpp"

namespace millwatch::shell {

struct ReportFiles {
  std::vector<std::filesystem::path> written;
  std::string plot_problem;  ///< why the plots are missing ("" if drawn)
};

/// Writes the report into `dir` (created). @throws std::runtime_error naming a file that cannot
/// be written. A missing or failing gnuplot leaves the plots out (said in the report).
ReportFiles write_diagnosis_report(const diagnose::Diagnosis& d, const std::filesystem::path& dir,
                                   const std::string& title, bool plots = true);

}  // namespace millwatch::shell
