#include "tests/support/test_paths.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>

namespace millwatch::test {

std::filesystem::path source_dir() {
  return MILLWATCH_SOURCE_DIR;
}

std::filesystem::path shared_dir() {
  if (const char* env = std::getenv("MILLWATCH_SHARED_DIR"); env != nullptr && *env != '\0') {
    return env;
  }
  return source_dir() / ".." / "shared";
}

std::filesystem::path fresh_temp_dir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  // One folder per build tree and test: builds of other checkouts on this machine run the same
  // tests at the same time.
  char build[17];
  std::snprintf(build, sizeof build, "%016zx", std::hash<std::string>{}(MILLWATCH_CLI));
  std::string name = std::string("millwatch_test_") + build;
  if (info != nullptr) {
    name += std::string("_") + info->test_suite_name() + "_" + info->name();
  }
  for (char& c : name) {
    if (c == '/') {
      c = '_';
    }
  }
  const auto dir = std::filesystem::temp_directory_path() / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

std::string read_text(const std::filesystem::path& path) {
  std::stringstream s;
  s << std::ifstream(path).rdbuf();
  return s.str();
}

}  // namespace millwatch::test
