#include "tests/support/private_network.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>

#include "tests/support/run_command.hpp"

namespace millwatch::test {
namespace {

constexpr const char* kInPrivateNetwork = "MILLWATCH_TEST_IN_PRIVATE_NETWORK";

}  // namespace

bool private_network_works(std::string& why) {
  const auto probe =
      run_command(std::string("unshare -n sh -c '") + kPrivateNetworkSetUp + "' 2>&1");
  why = probe.output;
  return probe.exit_code == 0;
}

bool in_private_network() {
  return std::getenv(kInPrivateNetwork) != nullptr;
}

void run_alone_in_private_network(const std::string& gtest_filter) {
  std::string why;
  if (!private_network_works(why)) {
    GTEST_SKIP() << "no private network namespace here (unshare -n): " << why;
  }
  const std::string self = std::filesystem::read_symlink("/proc/self/exe").string();
  const auto r = run_command(std::string(kInPrivateNetwork) +
                             "=1 timeout -k 5 60 unshare -n sh -c '" + kPrivateNetworkSetUp +
                             " && exec " + self + " --gtest_filter=" + gtest_filter + "' 2>&1");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("[  PASSED  ] 1 test"), std::string::npos) << r.output;
}

}  // namespace millwatch::test
