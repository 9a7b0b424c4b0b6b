#pragma once
// An output file written under a temporary name and renamed into place only when complete,
// so that an error or an interrupted run never leaves a partial file behind.

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace millwatch::shell {

class OutputFile {
 public:
  /// Opens `<path>.partial` for writing. @throws std::runtime_error naming the path.
  explicit OutputFile(std::filesystem::path path);
  ~OutputFile();  ///< removes the partial file unless commit() succeeded
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  [[nodiscard]] std::FILE* stream() { return file_; }
  void write(const std::string& text);
  /// Flushes, closes and renames to the final path. @throws std::runtime_error on failure.
  void commit();
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  std::filesystem::path partial_;
  std::FILE* file_ = nullptr;
  std::unique_ptr<char[]> buffer_;
  bool committed_ = false;
};

/// Checks, before any work, that an output file can be written at `path` (given with `option`,
/// e.g. "--summary"): not a folder, its folder there and writable (an existing file is
/// replaced by a rename: it need not be writable itself). @throws std::runtime_error naming the
/// option, the path and why.
/// `if_folder`: what to say when it is a folder.
void check_output_file(const std::string& option, const std::filesystem::path& path,
                       const std::string& if_folder = "a folder, not a file");
/// The same for an output folder: made now if missing (with its parents), and writable.
/// `purpose`: what it holds, for the messages ("the plots": "a file, not a folder for the
/// plots"; "" says only "a folder").
void check_output_folder(const std::string& option, const std::filesystem::path& path,
                         const std::string& purpose = "");

/// Writes `text` to `path` through an OutputFile. @throws std::runtime_error naming the path.
void write_text_file(const std::filesystem::path& path, const std::string& text);

/// Names for per-cut outputs (files, folders): each input's stem, made unique ("cut", "cut_2"),
/// each control character in it (a line break) replaced by _.
std::vector<std::string> unique_stems(const std::vector<std::string>& inputs);

}  // namespace millwatch::shell
