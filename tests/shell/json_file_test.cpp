// JSON files and text as the shells read them: errors name the file, the line and column, and
// (for a number beyond a double) the field; nesting is bounded.

#include "shell/json_file.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <stdexcept>
#include <string>

#include "core/monitor/monitor_config.hpp"
#include "tests/support/test_paths.hpp"

namespace millwatch::shell {
namespace {

std::string error_of(const std::string& text) {
  try {
    parse_json_text(text, "mem.json");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

std::string nested(std::size_t depth, const std::string& inner = "1") {
  return std::string(depth, '[') + inner + std::string(depth, ']');
}

TEST(JsonFile, ParsesAConfiguration) {
  const nlohmann::json j = parse_json_text(
      R"({"model": {"effects": {"dynamometer": {"natural_hz": [4500, 4600]}}}})", "mem.json");
  EXPECT_EQ(j["model"]["effects"]["dynamometer"]["natural_hz"][1], 4600);
}

TEST(JsonFile, ErrorsNameTheLineColumnAndField) {
  EXPECT_EQ(
      error_of("{\n  \"a\": 1,\n}").rfind("mem.json: JSON syntax error at line 3, column 1: ", 0),
      0u)
      << error_of("{\n  \"a\": 1,\n}");
  // The position once, and nlohmann's own words without its exception tag.
  const std::string syntax = error_of("{\n  \"a\": 1,\n}");
  EXPECT_EQ(syntax.find("column"), syntax.rfind("column")) << syntax;
  EXPECT_EQ(syntax.find("[json.exception"), std::string::npos) << syntax;
  EXPECT_NE(syntax.find(": syntax error while parsing object key"), std::string::npos) << syntax;
  const std::string not_finite = error_of(R"({"a": {"b": 1e400}})");
  EXPECT_NE(not_finite.find("mem.json: line 1, column"), std::string::npos) << not_finite;
  EXPECT_NE(not_finite.find("a.b: value 1e400 is not a finite number"), std::string::npos)
      << not_finite;
}

// A folder given for a configuration is said to be one (it had read as "JSON syntax error at
// line 1").
TEST(JsonFile, AFolderIsSaidToBeOne) {
  const auto dir = test::fresh_temp_dir();
  try {
    read_json_file(dir);
    ADD_FAILURE() << "a folder was read";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), dir.string() + ": a folder, not a JSON file");
  }
}

// 100,000 nested arrays used to overflow the stack as soon as a configuration reader quoted the
// value in its error (nlohmann's dump() recurses per level): found with the fuzz targets'
// harness on a crafted input.
TEST(JsonFile, NestingDeeperThanTheLimitIsAnErrorNotAStackOverflow) {
  EXPECT_NO_THROW(parse_json_text(nested(kMaxJsonDepth), "mem.json"));
  EXPECT_EQ(error_of("{\"model\":\n " + nested(kMaxJsonDepth)),
            "mem.json: JSON nested deeper than 64 levels at line 2, column 65");
  EXPECT_EQ(error_of(nested(100000)),
            "mem.json: JSON nested deeper than 64 levels at line 1, column 65");
  // Brackets in strings do not nest; escaped quotes do not end a string.
  const std::string in_string = "{\"name\": \"\\\"" + std::string(100, '[') + "\"}";
  EXPECT_EQ(parse_json_text(in_string, "mem.json")["name"].get<std::string>().size(), 101u);

  const auto dir = test::fresh_temp_dir();
  std::ofstream(dir / "deep.json") << "{\"spindle\": " << nested(100000) << "}";
  try {
    monitor::monitor_config_from_json(read_json_file(dir / "deep.json"));
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("deep.json: JSON nested deeper than 64 levels at line 1"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace millwatch::shell
