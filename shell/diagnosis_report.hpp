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

#include "core/diagnose/across_feeds.hpp"
#include "core/diagnose/diagnosis.hpp"

namespace millwatch::shell {

struct ReportFiles {
  std::vector<std::filesystem::path> written;
  std::string plot_problem;  ///< why the plots are missing ("" if drawn)
};

/// "v ± σ" with v to σ's second significant digit (at least 4): "24749.998 ± 0.001", so that the
/// estimate can be read to its uncertainty; "v" alone (4 digits) without a σ.
std::string value_sigma(double v, double sigma);

/// Writes the report into `dir` (created). @throws std::runtime_error naming a file that cannot
/// be written. A missing or failing gnuplot leaves the plots out (said in the report).
ReportFiles write_diagnosis_report(const diagnose::Diagnosis& d, const std::filesystem::path& dir,
                                   const std::string& title, bool plots = true);

/// One cut of a several-cut diagnosis: its name and the folder of its own report (relative to
/// the top report's folder).
struct CutReport {
  std::string name;
  std::string folder;
  const diagnose::Diagnosis* diagnosis = nullptr;
};

/// The report across feeds (`millwatch diagnose CUT1 CUT2 …`), each cut's own report being in
/// its folder already: DIR/report.json (cuts [{cut, feed_per_tooth_um, report, named_effects,
/// verdict, initial/final residual, noise floor}], across_feeds (diagnosis_json.hpp),
/// named_effects: those named in every cut, verdict), report.md/.html (the across-feeds table,
/// the trend, links to each cut's report) and residual_vs_feed.png (the residual's excess over
/// the noise against the feed, before and after, with the noise floor).
ReportFiles write_across_feeds_report(const diagnose::AcrossFeeds& across,
                                      const std::vector<CutReport>& cuts,
                                      const std::filesystem::path& dir, bool plots = true);

}  // namespace millwatch::shell
