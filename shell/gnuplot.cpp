#include "shell/gnuplot.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string_view>

namespace millwatch::shell {

std::string gnuplot_quoted(const std::filesystem::path& file) {
  const std::string name = file.string();
  for (const char c : name) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
      // gnuplot would end the string and the command at a line break: what follows would be a
      // command of its own (one starting with ! runs in the shell).
      throw std::invalid_argument("gnuplot cannot be given the path " + gnuplot_text(name, false) +
                                  ": it holds a line break or another control character");
    }
  }
  return gnuplot_text(name, false);  // with no control character: the name as it is, quoted
}

std::string gnuplot_text(std::string_view text, bool enhanced) {
  std::string out = "'";
  for (const char c : text) {
    if (c == '\'') {
      out += "''";
    } else if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
      out += ' ';
    } else {
      if (enhanced && std::string_view("_^{}@&~\\").find(c) != std::string_view::npos) {
        out += '\\';
      }
      out += c;
    }
  }
  return out + "'";
}

std::string run_gnuplot(const std::filesystem::path& script, const std::filesystem::path& log) {
  // The log opened here: a log that cannot be written is said as such, not as gnuplot missing.
  const std::string log_s = log.string();
  const int log_fd = ::open(log_s.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (log_fd < 0) {
    return "cannot write gnuplot's log " + log_s + " (" + std::strerror(errno) + ")";
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, log_fd, 2);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  std::string program = "gnuplot";
  std::string script_s = script.string();
  char* argv[] = {program.data(), script_s.data(), nullptr};
  pid_t pid = 0;
  const int rc = posix_spawnp(&pid, "gnuplot", &actions, nullptr, argv, environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(log_fd);
  if (rc != 0) {
    return std::string("cannot run gnuplot (") + std::strerror(rc) +
           "); install it (Debian: gnuplot-nox)";
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) {
      return "gnuplot on " + script_s + " could not be waited for (" + std::strerror(errno) + ")";
    }
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    return "gnuplot failed on " + script_s + "; see " + log_s;
  }
  return "";
}

}  // namespace millwatch::shell
