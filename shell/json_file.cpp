#include "shell/json_file.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace millwatch::shell {
namespace {

using json = nlohmann::json;

/// Builds the DOM like nlohmann's own parser while tracking the key path, so that a value the
/// parser rejects (a number too large for a double, i.e. not finite) is reported by field name.
class PathTrackingSax {
 public:
  explicit PathTrackingSax(json& result) : dom_(result, true) {}

  bool null() { return scalar(dom_.null()); }
  bool boolean(bool v) { return scalar(dom_.boolean(v)); }
  bool number_integer(json::number_integer_t v) { return scalar(dom_.number_integer(v)); }
  bool number_unsigned(json::number_unsigned_t v) { return scalar(dom_.number_unsigned(v)); }
  bool number_float(json::number_float_t v, const json::string_t& s) {
    return scalar(dom_.number_float(v, s));
  }
  bool string(json::string_t& v) { return scalar(dom_.string(v)); }
  bool binary(json::binary_t& v) { return scalar(dom_.binary(v)); }
  bool start_object(std::size_t n) {
    frames_.push_back({false, {}, 0});
    return dom_.start_object(n);
  }
  bool key(json::string_t& k) {
    frames_.back().key = k;
    return dom_.key(k);
  }
  bool end_object() {
    frames_.pop_back();
    return scalar(dom_.end_object());
  }
  bool start_array(std::size_t n) {
    frames_.push_back({true, {}, 0});
    return dom_.start_array(n);
  }
  bool end_array() {
    frames_.pop_back();
    return scalar(dom_.end_array());
  }
  bool parse_error(std::size_t position, const std::string& token,
                   const nlohmann::detail::exception& e) {
    position_ = position;
    not_finite_ = e.id == 406;
    if (not_finite_) {  // number overflow: the value is not a finite double
      message_ = path() + ": value " + token + " is not a finite number";
    } else {
      // nlohmann's text repeats the position the caller states: "[json.exception.parse_error.101]
      // parse error at line 1, column 56: syntax error while parsing …" — the part after it.
      message_ = e.what();
      const std::size_t column = message_.find("column ");
      const std::size_t colon = message_.find(": ", column == std::string::npos ? 0 : column);
      if (column != std::string::npos && colon != std::string::npos) {
        message_.erase(0, colon + 2);
      }
    }
    return false;
  }

  [[nodiscard]] const std::string& message() const { return message_; }
  [[nodiscard]] std::size_t position() const { return position_; }
  [[nodiscard]] bool not_finite() const { return not_finite_; }

 private:
  struct Frame {
    bool array;
    std::string key;
    std::size_t index;
  };

  bool scalar(bool ok) {
    if (!frames_.empty() && frames_.back().array) {
      ++frames_.back().index;
    }
    return ok;
  }

  [[nodiscard]] std::string path() const {
    std::string p;
    for (const auto& f : frames_) {
      if (f.array) {
        p.push_back('[');
        p.append(std::to_string(f.index)).push_back(']');
      } else {
        if (!p.empty()) {
          p.push_back('.');
        }
        p.append(f.key);
      }
    }
    return p.empty() ? "(top level)" : p;
  }

  nlohmann::detail::json_sax_dom_parser<json> dom_;
  std::vector<Frame> frames_;
  std::string message_;
  std::size_t position_ = 0;
  bool not_finite_ = false;
};

std::string line_and_column(const std::string& text, std::size_t byte) {
  const std::size_t at = std::min<std::size_t>(byte == 0 ? 0 : byte - 1, text.size());
  std::size_t line = 1;
  std::size_t column = 1;
  for (std::size_t i = 0; i < at; ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  return "line " + std::to_string(line) + ", column " + std::to_string(column);
}

/// Byte offset of the first '[' or '{' (outside strings) nested deeper than `max_depth`, or
/// npos.
std::size_t too_deep(const std::string& text, std::size_t max_depth) {
  std::size_t depth = 0;
  bool in_string = false;
  bool escaped = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (escaped) {
        escaped = false;
      } else if (c == '\\') {
        escaped = true;
      } else if (c == '"') {
        in_string = false;
      }
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > max_depth) {
        return i;
      }
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    }
  }
  return std::string::npos;
}

}  // namespace

nlohmann::json read_json_file(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw std::runtime_error(path.string() + ": a folder, not a JSON file");
  }
  std::ifstream in(path);
  if (!in) {
    throw std::runtime_error(path.string() + ": cannot read: " + std::strerror(errno));
  }
  std::stringstream text;
  text << in.rdbuf();
  return parse_json_text(text.str(), path.string());
}

nlohmann::json parse_json_text(const std::string& text, const std::string& name) {
  if (const std::size_t at = too_deep(text, kMaxJsonDepth); at != std::string::npos) {
    throw std::runtime_error(name + ": JSON nested deeper than " + std::to_string(kMaxJsonDepth) +
                             " levels at " + line_and_column(text, at + 1));
  }
  json result;
  PathTrackingSax sax(result);
  if (!json::sax_parse(text, &sax)) {
    const std::string what = sax.not_finite() ? ": " : ": JSON syntax error at ";
    throw std::runtime_error(name + what + line_and_column(text, sax.position()) + ": " +
                             sax.message());
  }
  return result;
}

}  // namespace millwatch::shell
