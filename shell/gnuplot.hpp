#pragma once
// Drawing with gnuplot (Debian's gnuplot-nox): the replay's plots and the diagnosis's report run
// a script they wrote, gnuplot's messages kept in a log beside it.

#include <filesystem>
#include <string>
#include <string_view>

namespace millwatch::shell {

/// A file name as a gnuplot string: in single quotes, each quote in it doubled. Throws
/// std::invalid_argument for a name with a control character (a line break would end gnuplot's
/// command there).
std::string gnuplot_quoted(const std::filesystem::path& file);

/// Any text (a title made of a file name, a stage's name) as a gnuplot string read literally: in
/// single quotes, where gnuplot substitutes no `command` and no escape, each quote in it doubled
/// and each control character a space. For an enhanced-text terminal, its markup characters
/// (_ ^ { } @ & ~ \) each get the backslash that makes them plain.
std::string gnuplot_text(std::string_view text, bool enhanced);

/// Runs `gnuplot script`, its standard error into `log` (its standard output discarded), and
/// waits for it. "" when it drew, else why not (not installed, or failed: see the log).
std::string run_gnuplot(const std::filesystem::path& script, const std::filesystem::path& log);

}  // namespace millwatch::shell
