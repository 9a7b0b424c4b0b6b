#pragma once
// Runs a shell command for tests of the command-line programs.

#include <string>

namespace millwatch::test {

struct CommandResult {
  int exit_code = -1;
  std::string output;  ///< stdout and stderr together
};

CommandResult run_command(const std::string& command);

/// Path of the `millwatch` program built with the tests.
inline std::string millwatch_cli() {
  return MILLWATCH_CLI;
}

/// The `millwatch` program for a test whose cost is the optimised computation itself and whose
/// code the sanitized tests also run elsewhere (the cp-Ti preset's diagnosis end to end: about
/// three minutes of a core under AddressSanitizer, about one optimised beside the rest of the
/// suite; the search and a final h_min profile run sanitized in tests/diagnose, on cuts whose
/// cycles fit in 64 revolutions; the real cut's diagnosis and calibration and the PHM windows'
/// campaign, 3.5× their optimised time sanitized): $MILLWATCH_OPTIMISED_CLI when set —
/// scripts/test.sh sets the Release program it has just built from the same sources and
/// checked (build/shipped) —, else millwatch_cli().
/// @throws std::runtime_error when $MILLWATCH_OPTIMISED_CLI names no file
std::string optimised_millwatch_cli();

}  // namespace millwatch::test
