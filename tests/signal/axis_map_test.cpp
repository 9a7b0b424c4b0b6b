#include "core/signal/axis_map.hpp"

#include <gtest/gtest.h>

#include "core/config/json_reader.hpp"

namespace millwatch::signal {
namespace {

TEST(AxisMap, DefaultIsADynamometerUnderTheWorkpiece) {
  const AxisMap m;
  const auto model = m.to_model({1.0, -2.0, 3.0});
  EXPECT_EQ(model, (std::array<double, 3>{-1.0, 2.0, -3.0}));
  EXPECT_EQ(m.to_reading(model), (std::array<double, 3>{1.0, -2.0, 3.0}));
}

TEST(AxisMap, PermutationAndSignsFromJsonRoundTrip) {
  const AxisMap m = axis_map_from_json({{"x", "+fy"}, {"y", "-fx"}, {"z", "fz"}}, "axis_map");
  const std::array<double, 3> reading = {1.0, 2.0, 3.0};
  EXPECT_EQ(m.to_model(reading), (std::array<double, 3>{2.0, -1.0, 3.0}));
  EXPECT_EQ(m.to_reading(m.to_model(reading)), reading);
  EXPECT_EQ(to_json(axis_map_from_json(to_json(m), "")), to_json(m));
}

TEST(AxisMap, RejectsRepeatedOrUnknownChannels) {
  EXPECT_THROW(axis_map_from_json({{"x", "fx"}, {"y", "fx"}}, "axis_map"), config::ConfigError);
  EXPECT_THROW(axis_map_from_json({{"x", "fq"}}, "axis_map"), config::ConfigError);
  EXPECT_THROW(axis_map_from_json({{"w", "fx"}}, "axis_map"), config::ConfigError);
}

}  // namespace
}  // namespace millwatch::signal
