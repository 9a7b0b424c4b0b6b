#pragma once
// Where tests find files that are not in the repository.

#include <filesystem>

namespace millwatch::test {

/// The project's source tree (config/ presets live there).
std::filesystem::path source_dir();

/// The shared folder beside the checkout (../shared): papers and real recordings. The
/// environment variable MILLWATCH_SHARED_DIR overrides the default.
std::filesystem::path shared_dir();

/// A fresh, empty temporary directory unique to the calling test and this build tree.
std::filesystem::path fresh_temp_dir();

}  // namespace millwatch::test
