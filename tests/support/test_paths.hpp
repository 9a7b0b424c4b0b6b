#pragma once
// Where tests find files that are not in the repository, and the text of one a program wrote.

#include <filesystem>
#include <string>

namespace millwatch::test {

/// The project's source tree (config/ presets live there).
std::filesystem::path source_dir();

/// The shared folder beside the checkout (../shared): papers and real recordings. The
/// environment variable MILLWATCH_SHARED_DIR overrides the default.
std::filesystem::path shared_dir();

/// A fresh, empty temporary directory unique to the calling test and this build tree.
std::filesystem::path fresh_temp_dir();

/// The whole text of a file (empty if it cannot be read: a log a program did not write).
std::string read_text(const std::filesystem::path& path);

}  // namespace millwatch::test
