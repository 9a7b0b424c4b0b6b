#include "core/config/json_reader.hpp"

#include <gtest/gtest.h>

#include <functional>
#include <limits>

namespace millwatch::config {
namespace {

using nlohmann::json;

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(JsonReader, ReadsValuesAndDefaults) {
  const json j = {{"diameter_mm", 0.8}, {"flutes", 3}, {"name", "t"}};
  ObjectReader r(j, "tool");
  EXPECT_DOUBLE_EQ(r.number("diameter_mm", 1.0, positive(50.0, "mm")), 0.8);
  EXPECT_EQ(r.integer("flutes", 2, 1, 8), 3);
  EXPECT_EQ(r.string("name", "x"), "t");
  EXPECT_DOUBLE_EQ(r.number("helix_deg", 30.0, closed(0, 60)), 30.0);
  EXPECT_NO_THROW(r.finish());
}

TEST(JsonReader, OutOfRangeNamesFieldValueAndRange) {
  const json j = {{"diameter_mm", -0.4}};
  ObjectReader r(j, "tool");
  const std::string msg = error_of([&] { r.number("diameter_mm", 1.0, positive(50.0, "mm")); });
  EXPECT_EQ(msg, "tool.diameter_mm: value -0.4 is out of range (0, 50] mm");
}

TEST(JsonReader, WrongTypeNamesFieldAndType) {
  const json j = {{"flutes", "two"}};
  ObjectReader r(j, "tool");
  const std::string msg = error_of([&] { r.integer("flutes", 2, 1, 8); });
  EXPECT_EQ(msg, "tool.flutes: expected an integer, got string \"two\"");
}

// A null said once ("got null null" had named the type and then its text).
TEST(JsonReader, WrongTypeNullIsSaidOnce) {
  const json j = {{"sample_rate_hz", nullptr}};
  ObjectReader r(j, "monitor");
  EXPECT_EQ(error_of([&] { r.number("sample_rate_hz", 1.0, positive(1e7, "Hz")); }),
            "monitor.sample_rate_hz: expected a number, got null");
}

TEST(JsonReader, IntegerZeroFlutesIsOutOfRange) {
  const json j = {{"flutes", 0}};
  ObjectReader r(j, "tool");
  EXPECT_EQ(error_of([&] { r.integer("flutes", 2, 1, 8); }),
            "tool.flutes: value 0 is out of range [1, 8]");
}

TEST(JsonReader, NonFiniteIsRejected) {
  json j;
  j["gain"] = std::numeric_limits<double>::infinity();
  ObjectReader r(j, "");
  EXPECT_NE(error_of([&] { r.number("gain", 1.0, closed(0, 10)); }).find("gain: value inf"),
            std::string::npos);
}

TEST(JsonReader, UnknownKeyIsRejectedWithAllowedList) {
  const json j = {{"diamter_mm", 0.4}};
  ObjectReader r(j, "tool");
  r.number("diameter_mm", 1.0, positive(50.0, "mm"));
  EXPECT_EQ(error_of([&] { r.finish(); }), "tool.diamter_mm: unknown key (allowed: diameter_mm)");
}

TEST(JsonReader, NestedObjectPathsAndChoices) {
  const json j = {{"process", {{"operation", "climb"}}}};
  ObjectReader r(j, "");
  auto p = r.object("process");
  EXPECT_EQ(error_of([&] {
              p.choice("operation", "slot", {"slot", "up", "down"});
            }),
            "process.operation: value \"climb\" is not one of: slot, up, down");
}

TEST(JsonReader, ArraysCheckEachElement) {
  const json j = {{"pitch_deg", {180.0, -1.0}}};
  ObjectReader r(j, "tool");
  EXPECT_EQ(error_of([&] { r.numbers("pitch_deg", {}, positive(360.0, "deg"), 0, 8); }),
            "tool.pitch_deg[1]: value -1 is out of range (0, 360] deg");
}

TEST(JsonReader, MissingRequiredNumber) {
  const json empty = json::object();
  ObjectReader r(empty, "daq");
  EXPECT_EQ(error_of([&] { r.required_number("sample_rate_hz", positive(1e6, "Hz")); }),
            "daq.sample_rate_hz: missing required number in (0, 1000000] Hz");
}

TEST(JsonReader, NonObjectIsRejected) {
  const json array = json::array();
  EXPECT_EQ(error_of([&] { ObjectReader r(array, "tool"); }),
            "tool: expected an object, got array []");
}

}  // namespace
}  // namespace millwatch::config
