#pragma once
// Drawing with gnuplot (Debian's gnuplot-nox): the replay's plots and the diagnosis's report run
// a script they wrote, gnuplot's messages kept in a log beside it.

#include <filesystem>
#include <string>

namespace millwatch::shell {

/// A file name as a gnuplot string: in single quotes, each quote in it doubled.
std::string gnuplot_quoted(const std::filesystem::path& file);

/// Runs `gnuplot script`, its standard error into `log` (its standard output discarded), and
/// waits for it. "" when it drew, else why not (not installed, or failed: see the log).
std::string run_gnuplot(const std::filesystem::path& script, const std::filesystem::path& log);

}  // namespace millwatch::shell
