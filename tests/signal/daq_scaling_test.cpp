#include "core/signal/daq_scaling.hpp"

#include <gtest/gtest.h>

#include "core/config/json_reader.hpp"

namespace millwatch::signal {
namespace {

// A 16-bit ±10 V DAQ on a charge amplifier set to 50 N full scale at ±10 V: 5 N/V.
TEST(DaqScaling, ConvertsCodesToNewtonsThroughBothRanges) {
  DaqChannelScaling c;
  c.range_N = 50.0;
  EXPECT_NEAR(c.scale(32768).force_N, (-10.0 + 20.0 * 32768 / 65535) * 5.0, 1e-9);  // ≈ 0
  EXPECT_NEAR(c.scale(49151).force_N, (-10.0 + 20.0 * 49151 / 65535) * 5.0, 1e-9);
  EXPECT_FALSE(c.scale(49151).saturated);
}

TEST(DaqScaling, FlagsDaqClippingAndAmplifierOverload) {
  DaqChannelScaling c;
  c.range_N = 50.0;
  EXPECT_TRUE(c.scale(0).saturated);
  EXPECT_EQ(c.scale(0).force_N, -50.0);
  EXPECT_TRUE(c.scale(65535).saturated);
  EXPECT_EQ(c.scale(65535).force_N, 50.0);
  // A DAQ wider than the amplifier: ±12 V range, amplifier overloads at ±10 V.
  c.volts_min = -12.0;
  c.volts_max = 12.0;
  const auto at_11V = static_cast<std::uint32_t>((11.0 + 12.0) / 24.0 * 65535);
  EXPECT_TRUE(c.scale(at_11V).saturated);
  EXPECT_EQ(c.scale(at_11V).force_N, 50.0);
}

TEST(DaqScaling, ConfigErrorsNameTheField) {
  const nlohmann::json j = {{"range_N", -5.0}};
  try {
    daq_channel_from_json(j, "source.channels[1]");
    FAIL();
  } catch (const config::ConfigError& e) {
    EXPECT_EQ(std::string(e.what()),
              "source.channels[1].range_N: value -5 is out of range (0, 1000000] N");
  }
}

}  // namespace
}  // namespace millwatch::signal
