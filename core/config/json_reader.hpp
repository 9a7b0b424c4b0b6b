#pragma once
// Strict reading of JSON configuration objects.
//
// Every configuration struct in millwatch is read through an ObjectReader: it checks each
// field's type and allowed range, fills defaults for absent optional fields, and rejects keys it
// does not know. Errors throw ConfigError whose message names the field's full path, the
// offending value and what is allowed, e.g.
//
//   tool.diameter_mm: value -0.4 is out of range (0, 50] mm
//   tool.flutes: expected an integer, got string "two"
//   process.spindel_rpm: unknown key (allowed: operation, spindle_rpm, ...)

#include <cstdint>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace millwatch::config {

/// Invalid configuration value; what() names the field path, the value and the allowed range.
class ConfigError : public std::runtime_error {
 public:
  ConfigError(std::string path, const std::string& message)
      : std::runtime_error(path + ": " + message), path_(std::move(path)) {}
  [[nodiscard]] const std::string& path() const { return path_; }

 private:
  std::string path_;
};

/// A closed or open interval with a unit for messages. Bounds are inclusive unless marked open.
struct Range {
  double min = 0.0;
  double max = 0.0;
  bool min_open = false;
  bool max_open = false;
  std::string_view unit;

  [[nodiscard]] bool contains(double v) const;
  [[nodiscard]] std::string describe() const;  ///< e.g. "(0, 50] mm"
};

/// Convenience constructors for ranges.
inline Range closed(double lo, double hi, std::string_view unit = "") {
  return {lo, hi, false, false, unit};
}
inline Range positive(double hi, std::string_view unit = "") {
  return {0.0, hi, true, false, unit};
}
inline Range non_negative(double hi, std::string_view unit = "") {
  return {0.0, hi, false, false, unit};
}

/// Reads fields of one JSON object. Call finish() after the last field to reject unknown keys.
class ObjectReader {
 public:
  /// @throws ConfigError if `value` is not an object. The reader refers to `value`, which must
  /// outlive it (hence no temporaries).
  ObjectReader(const nlohmann::json& value, std::string path);
  ObjectReader(nlohmann::json&& value, std::string path) = delete;

  [[nodiscard]] bool has(std::string_view key) const;

  /// A finite number within `range`; `fallback` when absent.
  double number(std::string_view key, double fallback, const Range& range);
  /// A finite number within `range`; absent is an error.
  double required_number(std::string_view key, const Range& range);
  /// An integer within [min, max]; `fallback` when absent.
  int integer(std::string_view key, int fallback, int min, int max);
  std::int64_t integer64(std::string_view key, std::int64_t fallback, std::int64_t min,
                         std::int64_t max);
  bool boolean(std::string_view key, bool fallback);
  /// A string; `fallback` when absent.
  std::string string(std::string_view key, const std::string& fallback);
  /// One of `allowed`; `fallback` when absent.
  std::string choice(std::string_view key, const std::string& fallback,
                     std::initializer_list<std::string_view> allowed);
  /// An array of finite numbers, each within `range`, of length in [min_size, max_size];
  /// `fallback` when absent.
  std::vector<double> numbers(std::string_view key, const std::vector<double>& fallback,
                              const Range& range, std::size_t min_size, std::size_t max_size);
  /// A nested object (an empty one when absent), for a nested ObjectReader.
  ObjectReader object(std::string_view key);
  /// The raw JSON value of a present key (marks it used); null when absent.
  const nlohmann::json& raw(std::string_view key);

  /// Full path of a field of this object, for error messages ("tool.diameter_mm").
  [[nodiscard]] std::string path_of(std::string_view key) const;
  [[nodiscard]] const std::string& path() const { return path_; }

  /// @throws ConfigError naming the first key that no accessor asked for.
  void finish() const;

 private:
  const nlohmann::json* find(std::string_view key);

  const nlohmann::json& value_;
  std::string path_;
  std::vector<std::string> known_;
};

/// Short description of a JSON value's type and content for messages: `string "two"`.
std::string describe_json(const nlohmann::json& value);

/// A number as the messages print it (10 significant digits): `0.25`, `-1`.
std::string format_number(double v);

/// Throws ConfigError(path, message) — for cross-field checks done after reading.
[[noreturn]] void fail(const std::string& path, const std::string& message);

}  // namespace millwatch::config
