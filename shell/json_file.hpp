#pragma once
// Reading a JSON file with errors that name the file and the line.

#include <cstddef>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

namespace millwatch::shell {

/// Deepest nesting of arrays and objects accepted. A configuration needs 6; deeper ones are
/// refused because nlohmann's serializer (error messages quote values) recurses per level: a
/// file of 100,000 '[' overflowed the stack.
inline constexpr std::size_t kMaxJsonDepth = 64;

/// @throws std::runtime_error "PATH: cannot read ...", "PATH: JSON syntax error at line L,
/// column C: ..." or "PATH: JSON nested deeper than 64 levels at line L, column C".
nlohmann::json read_json_file(const std::filesystem::path& path);

/// The same for JSON text already in memory, named `name` in errors.
nlohmann::json parse_json_text(const std::string& text, const std::string& name);

}  // namespace millwatch::shell
