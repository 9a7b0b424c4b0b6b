#pragma once
// Tests that send on udpm:// run in a private network namespace (unshare -n, its loopback up and
// a multicast route on it), so that no packet leaves the machine; where the machine does not
// permit one they are skipped, saying why.

#include <string>

namespace millwatch::test {

/// The commands that give a fresh namespace its loopback and a multicast route.
inline constexpr const char* kPrivateNetworkSetUp =
    "ip link set lo up && ip route add 239.0.0.0/8 dev lo";

/// Whether this machine lets us make one; `why` gets what refused it.
bool private_network_works(std::string& why);

/// Whether this process runs in one that run_alone_in_private_network() made.
bool in_private_network();

/// Runs the test `gtest_filter` names again, alone, in a private network namespace (bounded to
/// 60 s) and checks that it passed; skips the calling test, saying why, where none can be made.
/// The calling test returns after it, and does its work when in_private_network().
void run_alone_in_private_network(const std::string& gtest_filter);

}  // namespace millwatch::test
