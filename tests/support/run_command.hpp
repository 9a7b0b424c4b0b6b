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

}  // namespace millwatch::test
