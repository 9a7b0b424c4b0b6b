// A DAQ board's whole-nanosecond scan period against the configured sample rate.

#include "daemon/scan_timing.hpp"

#include <gtest/gtest.h>

namespace millwatch::daemon {
namespace {

TEST(ScanTiming, AsksForTheNearestWholeNanosecondPeriod) {
  EXPECT_EQ(scan_period_ns(50000.0), 20000u);
  EXPECT_EQ(scan_period_ns(333300.0), 3000u);      // 3,000.3 ns
  EXPECT_EQ(scan_period_ns(1e9 / 2999.6), 3000u);  // rounded, not truncated to 2,999
  EXPECT_EQ(scan_period_ns(20000.0), 50000u);
}

TEST(ScanTiming, ARateTheBoardKeepsPasses) {
  EXPECT_EQ(scan_rate_mismatch(50000.0, 20000), "");
  EXPECT_EQ(scan_rate_mismatch(1e9 / 3000.0, 3000), "");
  EXPECT_EQ(scan_rate_mismatch(333333.333333, 3000), "");  // as printed: within 1e-6
}

// 333,300 Hz on a 3,000 ns scan is 333,333.3 Hz: 0.01 % off, said with the setting that fits.
TEST(ScanTiming, ARateTheBoardRoundsIsRefusedWithTheRateItGives) {
  const std::string why = scan_rate_mismatch(333300.0, 3000);
  EXPECT_NE(why.find("every 3000 ns (333333.333333 Hz)"), std::string::npos) << why;
  EXPECT_NE(why.find("monitor.sample_rate_hz 333300 Hz"), std::string::npos) << why;
  EXPECT_NE(why.find("+0.0100 % off"), std::string::npos) << why;
  EXPECT_NE(why.find("set monitor.sample_rate_hz to 333333.333333"), std::string::npos) << why;
  // A board that stretches the period (its fastest scan is slower than asked).
  const std::string slow = scan_rate_mismatch(333300.0, 4000);
  EXPECT_NE(slow.find("-24.9925 % off"), std::string::npos) << slow;
  EXPECT_NE(scan_rate_mismatch(50000.0, 0), "");
}

}  // namespace
}  // namespace millwatch::daemon
