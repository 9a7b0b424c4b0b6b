#pragma once
// A campaign of cuts (`millwatch replay CUT1 CUT2 ... --table cuts.csv`): one row per cut from
// its run summary — file, status, samples, duration, speed, revolutions, α mean and std, each
// flute's mean peak in-plane force, ΔFy, residual RMS per axis, the alerts raised and the
// warnings' kinds (why a value is absent, e.g. "no steady tooth-passing signal").

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace millwatch::shell {

struct CutResult {
  std::string file;
  int exit_code = 0;       ///< of the cut's replay (non-zero: failed, summary null; or interrupted)
  nlohmann::json summary;  ///< the cut's summary JSON (null if it failed; partial if interrupted)
  std::string error;       ///< why it failed, as its replay said (empty: not known)
};

/// The table as CSV (a header and one row per cut; absent values are empty fields).
std::string cut_table_csv(const std::vector<CutResult>& cuts);
/// The same, aligned for a terminal.
std::string cut_table_text(const std::vector<CutResult>& cuts);

}  // namespace millwatch::shell
