#include "shell/column_map.hpp"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <stdexcept>

namespace millwatch::shell {
namespace {

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t");
  if (a == std::string::npos) {
    return "";
  }
  const auto b = s.find_last_not_of(" \t");
  return s.substr(a, b - a + 1);
}

bool parse_double(const std::string& s, double& v) {
  const char* first = s.data();
  const char* last = s.data() + s.size();
  if (first != last && *first == '+') {
    ++first;
  }
  const auto r = std::from_chars(first, last, v);
  return r.ec == std::errc() && r.ptr == last && std::isfinite(v);
}

/// "Fx*1000", "3", "F(:,1)*-1" → spec.
ColumnSpec parse_spec(const std::string& key, const std::string& text, const std::string& path) {
  ColumnSpec spec;
  std::string source = trim(text);
  if (const auto star = source.rfind('*'); star != std::string::npos) {
    const std::string scale = trim(source.substr(star + 1));
    if (!parse_double(scale, spec.scale) || spec.scale == 0.0) {
      throw std::invalid_argument(path + ": " + key + ": scale \"" + scale +
                                  "\" is not a finite non-zero number");
    }
    source = trim(source.substr(0, star));
    spec.scaled = true;
  }
  if (source.empty()) {
    throw std::invalid_argument(path + ": " + key + ": no column named");
  }
  if (source.find_first_not_of("0123456789") == std::string::npos) {
    int index = 0;
    const auto r = std::from_chars(source.data(), source.data() + source.size(), index);
    if (r.ec != std::errc() || index < 1 || index > 100000) {
      throw std::invalid_argument(path + ": " + key + ": column index " + source +
                                  " is out of range [1, 100000]");
    }
    spec.index = index;
  } else {
    spec.source = source;
  }
  return spec;
}

std::size_t key_index(const std::string& key, const std::string& path) {
  for (std::size_t i = 0; i < ColumnMap::kKeys.size(); ++i) {
    if (key == ColumnMap::kKeys[i]) {
      return i;
    }
  }
  throw std::invalid_argument(path + ": unknown key \"" + key + "\" (allowed: t, fx, fy, fz, fs)");
}

void check_complete(const ColumnMap& m, const std::string& path) {
  if (m.empty()) {
    return;
  }
  for (int a = 0; a < 3; ++a) {
    if (!m.force(a).given()) {
      throw std::invalid_argument(path + ": " + ColumnMap::kKeys[static_cast<std::size_t>(1 + a)] +
                                  " is missing (fx, fy and fz are all needed; t and fs are "
                                  "optional)");
    }
  }
  // One column read as two quantities (fx=1,fy=1) would measure a cut that was not recorded.
  for (std::size_t i = 0; i < 4; ++i) {
    for (std::size_t k = i + 1; k < 4; ++k) {
      const ColumnSpec& a = m.column[i];
      const ColumnSpec& b = m.column[k];
      if (a.given() && b.given() && a.index == b.index && a.source == b.source) {
        throw std::invalid_argument(path + ": " + ColumnMap::kKeys[i] + " and " +
                                    ColumnMap::kKeys[k] + " both read " + a.describe_source() +
                                    " (each needs its own column)");
      }
    }
  }
}

}  // namespace

std::string ColumnSpec::describe_source() const {
  return index > 0 ? std::to_string(index) : source;
}

bool ColumnMap::empty() const {
  for (const auto& c : column) {
    if (c.given()) {
      return false;
    }
  }
  return true;
}

std::string ColumnMap::to_string() const {
  std::string s;
  for (std::size_t i = 0; i < column.size(); ++i) {
    if (!column[i].given()) {
      continue;
    }
    const ColumnSpec& c = column[i];
    if (!s.empty()) {
      s += ',';
    }
    s += kKeys[i];
    s += '=';
    s += c.describe_source();
    // A scale the map gave is written out, "*1" too (it says a units row's factor does not
    // apply), and so is a name's with a '*' of its own, so that it reads back the same.
    if (c.scaled || c.scale != 1.0 || c.source.find('*') != std::string::npos) {
      char text[32];
      const auto r = std::to_chars(text, text + sizeof text, c.scale);
      s += '*';
      s.append(text, r.ptr);
    }
  }
  return s;
}

ColumnMap parse_column_map(const std::string& text) {
  const std::string path = "columns";
  ColumnMap m;
  std::size_t from = 0;
  while (from <= text.size()) {
    std::size_t to = from;
    int depth = 0;  // commas inside F(:,1) belong to the entry
    while (to < text.size() && (text[to] != ',' || depth > 0)) {
      depth += text[to] == '(' ? 1 : text[to] == ')' ? -1 : 0;
      ++to;
    }
    const std::string entry = trim(text.substr(from, to - from));
    from = to + 1;
    if (entry.empty()) {
      continue;
    }
    const auto eq = entry.find('=');
    if (eq == std::string::npos) {
      throw std::invalid_argument(path + ": \"" + entry +
                                  "\" is not key=column (e.g. t=Time,fx=Fx,fy=Fy,fz=Fz)");
    }
    const std::string key = trim(entry.substr(0, eq));
    const std::size_t k = key_index(key, path);
    if (m.column[k].given()) {
      throw std::invalid_argument(path + ": " + key + " is given twice");
    }
    m.column[k] = parse_spec(key, entry.substr(eq + 1), path);
  }
  if (m.empty()) {
    throw std::invalid_argument(path + ": no columns named (e.g. t=Time,fx=Fx,fy=Fy,fz=Fz)");
  }
  check_complete(m, path);
  return m;
}

ColumnMap column_map_from_json(const nlohmann::json& j, const std::string& path) {
  if (j.is_string()) {
    try {
      return parse_column_map(j.get<std::string>());
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      throw std::invalid_argument(path + what.substr(std::string("columns").size()));
    }
  }
  if (!j.is_object()) {
    throw std::invalid_argument(path + ": expected text (\"t=Time,fx=Fx,...\") or an object, got " +
                                std::string(j.type_name()));
  }
  ColumnMap m;
  for (const auto& [key, value] : j.items()) {
    const std::size_t k = key_index(key, path);
    if (value.is_number_integer()) {
      m.column[k] = parse_spec(key, std::to_string(value.get<std::int64_t>()), path);
    } else if (value.is_string()) {
      m.column[k] = parse_spec(key, value.get<std::string>(), path);
    } else {
      throw std::invalid_argument(path + "." + key + ": expected a column name or index, got " +
                                  std::string(value.type_name()));
    }
  }
  if (m.empty()) {
    throw std::invalid_argument(path + ": no columns named");
  }
  check_complete(m, path);
  return m;
}

}  // namespace millwatch::shell
