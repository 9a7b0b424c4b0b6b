#include "tests/support/run_command.hpp"

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>

namespace millwatch::test {

CommandResult run_command(const std::string& command) {
  CommandResult result;
  const std::string full = command + " 2>&1";
  std::FILE* pipe = popen(full.c_str(), "r");
  if (pipe == nullptr) {
    return result;
  }
  std::array<char, 4096> buffer{};
  while (std::fgets(buffer.data(), static_cast<int>(buffer.size()), pipe) != nullptr) {
    result.output += buffer.data();
  }
  const int status = pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

std::string optimised_millwatch_cli() {
  const char* env = std::getenv("MILLWATCH_OPTIMISED_CLI");
  if (env == nullptr || *env == '\0') {
    return millwatch_cli();
  }
  if (!std::filesystem::is_regular_file(env)) {
    throw std::runtime_error(std::string("MILLWATCH_OPTIMISED_CLI: no program at ") + env);
  }
  return env;
}

}  // namespace millwatch::test
