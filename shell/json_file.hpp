#pragma once
// Reading a JSON file with errors that name the file and the line.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

namespace millwatch::shell {

/// @throws std::runtime_error "PATH: cannot read ..." or "PATH: JSON syntax error at line L,
/// column C: ...".
nlohmann::json read_json_file(const std::filesystem::path& path);

/// The same for JSON text already in memory, named `name` in errors.
nlohmann::json parse_json_text(const std::string& text, const std::string& name);

}  // namespace millwatch::shell
