#include "shell/output_file.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <map>
#include <stdexcept>
#include <system_error>

namespace millwatch::shell {

OutputFile::OutputFile(std::filesystem::path path)
    : path_(std::move(path)), partial_(path_.string() + ".partial") {
  file_ = std::fopen(partial_.c_str(), "wb");
  if (file_ == nullptr) {
    throw std::runtime_error("cannot write " + partial_.string() + ": " + std::strerror(errno));
  }
  constexpr std::size_t kBufferBytes = 1 << 16;
  buffer_ = std::make_unique<char[]>(kBufferBytes);
  std::setvbuf(file_, buffer_.get(), _IOFBF, kBufferBytes);
}

OutputFile::~OutputFile() {
  if (file_ != nullptr) {
    std::fclose(file_);
  }
  if (!committed_) {
    std::error_code ignored;
    std::filesystem::remove(partial_, ignored);
  }
}

void OutputFile::write(const std::string& text) {
  if (std::fwrite(text.data(), 1, text.size(), file_) != text.size()) {
    throw std::runtime_error("write to " + partial_.string() + " failed: " + std::strerror(errno));
  }
}

void OutputFile::commit() {
  const bool flushed = std::fflush(file_) == 0 && std::ferror(file_) == 0;
  const bool closed = std::fclose(file_) == 0;
  file_ = nullptr;
  if (!flushed || !closed) {
    throw std::runtime_error("write to " + partial_.string() + " failed: " + std::strerror(errno));
  }
  std::error_code ec;
  std::filesystem::rename(partial_, path_, ec);
  if (ec) {
    throw std::runtime_error("cannot rename " + partial_.string() + " to " + path_.string() + ": " +
                             ec.message());
  }
  committed_ = true;
}

namespace {

[[noreturn]] void refuse(const std::string& option, const std::filesystem::path& path,
                         const std::string& why) {
  throw std::runtime_error(option + " " + path.string() + ": " + why);
}

}  // namespace

void check_output_file(const std::string& option, const std::filesystem::path& path,
                       const std::string& if_folder) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    refuse(option, path, if_folder);
  }
  const fs::path folder = path.parent_path().empty() ? fs::path(".") : path.parent_path();
  if (!fs::is_directory(folder, ec)) {
    refuse(option, path, "no folder " + folder.string());
  }
  // The file goes in as <path>.partial, renamed into place: the folder must take new files.
  if (::access(folder.c_str(), W_OK | X_OK) != 0) {
    refuse(option, path, "cannot write in " + folder.string() + " (" + std::strerror(errno) + ")");
  }
}

void check_output_folder(const std::string& option, const std::filesystem::path& path,
                         const std::string& purpose) {
  namespace fs = std::filesystem;
  const std::string folder = purpose.empty() ? "folder" : "folder for " + purpose;
  std::error_code ec;
  if (fs::exists(path, ec) && !fs::is_directory(path, ec)) {
    refuse(option, path, "a file, not a " + folder);
  }
  fs::create_directories(path, ec);
  if (ec) {
    refuse(option, path, "cannot make the " + folder + " (" + ec.message() + ")");
  }
  if (::access(path.c_str(), W_OK | X_OK) != 0) {
    refuse(option, path, "cannot write in it (" + std::string(std::strerror(errno)) + ")");
  }
}

void write_text_file(const std::filesystem::path& path, const std::string& text) {
  OutputFile out(path);
  out.write(text);
  out.commit();
}

std::vector<std::string> unique_stems(const std::vector<std::string>& inputs) {
  std::vector<std::string> stems;
  std::map<std::string, int> seen;
  for (const auto& in : inputs) {
    std::string stem = std::filesystem::path(in).stem().string();
    for (char& c : stem) {  // a line break in a folder's name would break the scripts that plot
      c = static_cast<unsigned char>(c) < 0x20 || c == 0x7f ? '_' : c;
    }
    const int n = ++seen[stem];
    stems.push_back(n == 1 ? stem : stem + "_" + std::to_string(n));
  }
  return stems;
}

}  // namespace millwatch::shell
