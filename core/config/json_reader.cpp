#include "core/config/json_reader.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace millwatch::config {
namespace {

const nlohmann::json& empty_object() {
  static const nlohmann::json empty = nlohmann::json::object();
  return empty;
}

}  // namespace

std::string format_number(double v) {
  std::ostringstream out;
  out.precision(10);
  out << v;
  return out.str();
}

bool Range::contains(double v) const {
  const bool above = min_open ? v > min : v >= min;
  const bool below = max_open ? v < max : v <= max;
  return above && below;
}

std::string Range::describe() const {
  // Built by appending: GCC 12 reports a false -Wrestrict on chained operator+ here.
  std::string text(1, min_open ? '(' : '[');
  text.append(format_number(min)).append(", ").append(format_number(max));
  text.push_back(max_open ? ')' : ']');
  if (!unit.empty()) {
    text.push_back(' ');
    text.append(unit);
  }
  return text;
}

std::string describe_json(const nlohmann::json& value) {
  if (value.is_null()) {
    return "null";  // not "null null"
  }
  std::string dumped = value.dump();
  if (dumped.size() > 60) {
    dumped = dumped.substr(0, 57) + "...";
  }
  return std::string(value.type_name()) + " " + dumped;
}

void fail(const std::string& path, const std::string& message) {
  throw ConfigError(path, message);
}

ObjectReader::ObjectReader(const nlohmann::json& value, std::string path)
    : value_(value.is_null() ? empty_object() : value), path_(std::move(path)) {
  if (!value_.is_object()) {
    fail(path_.empty() ? "(top level)" : path_, "expected an object, got " + describe_json(value_));
  }
}

std::string ObjectReader::path_of(std::string_view key) const {
  return path_.empty() ? std::string(key) : path_ + "." + std::string(key);
}

bool ObjectReader::has(std::string_view key) const {
  return value_.contains(std::string(key));
}

const nlohmann::json* ObjectReader::find(std::string_view key) {
  known_.emplace_back(key);
  const auto it = value_.find(std::string(key));
  return it == value_.end() ? nullptr : &*it;
}

double ObjectReader::number(std::string_view key, double fallback, const Range& range) {
  const nlohmann::json* v = find(key);
  if (v == nullptr) {
    return fallback;
  }
  if (!v->is_number()) {
    fail(path_of(key), "expected a number, got " + describe_json(*v));
  }
  const double x = v->get<double>();
  if (!std::isfinite(x)) {
    fail(path_of(key), "value " + format_number(x) + " is not finite; allowed " + range.describe());
  }
  if (!range.contains(x)) {
    fail(path_of(key), "value " + format_number(x) + " is out of range " + range.describe());
  }
  return x;
}

double ObjectReader::required_number(std::string_view key, const Range& range) {
  if (!has(key)) {
    known_.emplace_back(key);
    fail(path_of(key), "missing required number in " + range.describe());
  }
  return number(key, 0.0, range);
}

std::int64_t ObjectReader::integer64(std::string_view key, std::int64_t fallback, std::int64_t min,
                                     std::int64_t max) {
  const nlohmann::json* v = find(key);
  if (v == nullptr) {
    return fallback;
  }
  const bool integral_float = v->is_number_float() && std::isfinite(v->get<double>()) &&
                              std::floor(v->get<double>()) == v->get<double>() &&
                              std::fabs(v->get<double>()) < 9e15;
  if (!v->is_number_integer() && !integral_float) {
    fail(path_of(key), "expected an integer, got " + describe_json(*v));
  }
  const std::int64_t x =
      integral_float ? static_cast<std::int64_t>(v->get<double>()) : v->get<std::int64_t>();
  if (x < min || x > max) {
    fail(path_of(key), "value " + std::to_string(x) + " is out of range [" + std::to_string(min) +
                           ", " + std::to_string(max) + "]");
  }
  return x;
}

int ObjectReader::integer(std::string_view key, int fallback, int min, int max) {
  return static_cast<int>(integer64(key, fallback, min, max));
}

bool ObjectReader::boolean(std::string_view key, bool fallback) {
  const nlohmann::json* v = find(key);
  if (v == nullptr) {
    return fallback;
  }
  if (!v->is_boolean()) {
    fail(path_of(key), "expected true or false, got " + describe_json(*v));
  }
  return v->get<bool>();
}

std::string ObjectReader::string(std::string_view key, const std::string& fallback) {
  const nlohmann::json* v = find(key);
  if (v == nullptr) {
    return fallback;
  }
  if (!v->is_string()) {
    fail(path_of(key), "expected a string, got " + describe_json(*v));
  }
  return v->get<std::string>();
}

std::string ObjectReader::choice(std::string_view key, const std::string& fallback,
                                 std::initializer_list<std::string_view> allowed) {
  std::string s = string(key, fallback);
  if (std::find(allowed.begin(), allowed.end(), s) == allowed.end()) {
    std::string list;
    for (std::string_view a : allowed) {
      list += (list.empty() ? "" : ", ") + std::string(a);
    }
    fail(path_of(key), "value \"" + s + "\" is not one of: " + list);
  }
  return s;
}

std::vector<double> ObjectReader::numbers(std::string_view key, const std::vector<double>& fallback,
                                          const Range& range, std::size_t min_size,
                                          std::size_t max_size) {
  const nlohmann::json* v = find(key);
  if (v == nullptr) {
    return fallback;
  }
  if (!v->is_array()) {
    fail(path_of(key), "expected an array of numbers, got " + describe_json(*v));
  }
  if (v->size() < min_size || v->size() > max_size) {
    fail(path_of(key), "array has " + std::to_string(v->size()) + " elements; allowed " +
                           std::to_string(min_size) + " to " + std::to_string(max_size));
  }
  std::vector<double> out;
  out.reserve(v->size());
  for (std::size_t i = 0; i < v->size(); ++i) {
    const auto& e = (*v)[i];
    const std::string at = path_of(key) + "[" + std::to_string(i) + "]";
    if (!e.is_number()) {
      fail(at, "expected a number, got " + describe_json(e));
    }
    const double x = e.get<double>();
    if (!std::isfinite(x) || !range.contains(x)) {
      fail(at, "value " + format_number(x) + " is out of range " + range.describe());
    }
    out.push_back(x);
  }
  return out;
}

ObjectReader ObjectReader::object(std::string_view key) {
  const nlohmann::json* v = find(key);
  return ObjectReader(v == nullptr ? empty_object() : *v, path_of(key));
}

const nlohmann::json& ObjectReader::raw(std::string_view key) {
  static const nlohmann::json null_value;
  const nlohmann::json* v = find(key);
  return v == nullptr ? null_value : *v;
}

void ObjectReader::finish() const {
  for (const auto& [key, unused] : value_.items()) {
    if (std::find(known_.begin(), known_.end(), key) == known_.end()) {
      std::string list;
      for (const auto& k : known_) {
        list += (list.empty() ? "" : ", ") + k;
      }
      fail(path_of(key), "unknown key (allowed: " + list + ")");
    }
  }
}

}  // namespace millwatch::config
