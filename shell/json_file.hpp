#pragma once
// Reading a JSON file with errors that name the file and the line.

#include <filesystem>
#include <nlohmann/json.hpp>

namespace millwatch::shell {

/// @throws std::runtime_error "PATH: cannot read ..." or "PATH: JSON syntax error at line L,
/// column C: ...".
nlohmann::json read_json_file(const std::filesystem::path& path);

}  // namespace millwatch::shell
