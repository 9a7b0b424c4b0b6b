#include "shell/isolated_call.hpp"

#include <fcntl.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdint>
#include <cstring>
#include <exception>
#include <fstream>
#include <new>

#if defined(__SANITIZE_ADDRESS__)
#define MILLWATCH_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define MILLWATCH_SANITIZED 1
#endif
#endif
#ifdef MILLWATCH_SANITIZED
#include <sanitizer/common_interface_defs.h>
#endif

namespace millwatch::shell {
namespace {

/// The child's exit status when a sanitizer stopped it (its report is not printed).
constexpr int kSanitizerStopped = 97;

/// Repeats `io(data, n)` (::read or ::write on a pipe) until all n bytes went through, as a
/// signal may interrupt it and a pipe passes a part at a time; false at an end of the pipe or an
/// error.
template <class Byte, class Io>
bool all_bytes(Byte* data, std::size_t n, Io io) {
  while (n > 0) {
    const ssize_t done = io(data, n);
    if (done < 0 && errno == EINTR) {
      continue;
    }
    if (done <= 0) {
      return false;
    }
    data += done;
    n -= static_cast<std::size_t>(done);
  }
  return true;
}

bool write_all(int fd, const char* data, std::size_t n) {
  return all_bytes(data, n, [fd](const char* p, std::size_t k) { return ::write(fd, p, k); });
}

/// Reads exactly n bytes; false at an early end of the pipe.
bool read_all(int fd, char* data, std::size_t n) {
  return all_bytes(data, n, [fd](char* p, std::size_t k) { return ::read(fd, p, k); });
}

void bound_child(std::size_t budget_bytes) {
#ifdef MILLWATCH_SANITIZED
  (void)budget_bytes;
  // A report (e.g. the allocator refusing 171 GB) ends the child, which the parent reports.
  const int null = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
  if (null >= 0) {
    __sanitizer_set_report_fd(reinterpret_cast<void*>(static_cast<std::intptr_t>(null)));
  }
  __sanitizer_set_death_callback(+[] { _exit(kSanitizerStopped); });
#else
  // The address space mapped now (VmSize) and the budget.
  std::ifstream statm("/proc/self/statm");
  std::size_t pages = 0;
  statm >> pages;
  const std::size_t bound = pages * static_cast<std::size_t>(sysconf(_SC_PAGESIZE)) + budget_bytes;
  const rlimit limit{bound, bound};
  setrlimit(RLIMIT_AS, &limit);
#endif
}

[[noreturn]] void child(int fd, const std::function<std::string()>& work,
                        std::size_t budget_bytes) {
  bound_child(budget_bytes);
  char tag = 'A';
  std::string out;
  try {
    out = work();
  } catch (const std::bad_alloc&) {
    tag = 'E';
    out = "out of memory (the reading process may map " + std::to_string(budget_bytes >> 20) +
          " MiB beyond what it started with)";
  } catch (const std::exception& e) {
    tag = 'E';
    out = e.what();
  }
  const std::uint64_t size = out.size();
  char header[9];
  header[0] = tag;
  std::memcpy(header + 1, &size, sizeof size);
  const bool ok = write_all(fd, header, sizeof header) && write_all(fd, out.data(), out.size());
  _exit(ok ? 0 : 1);
}

std::string how_it_ended(int status) {
  if (WIFSIGNALED(status)) {
    const int s = WTERMSIG(status);
    const char* name = strsignal(s);
    return "crashed (signal " + std::to_string(s) +
           (name != nullptr ? ", " + std::string(name) : "") + ")";
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) == kSanitizerStopped) {
    return "was stopped by a sanitizer";
  }
  if (WIFEXITED(status)) {
    return "exited (status " + std::to_string(WEXITSTATUS(status)) + ") without an answer";
  }
  return "ended without an answer";
}

int wait_for(pid_t pid) {
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return status;
}

}  // namespace

IsolatedResult run_isolated(const std::function<std::string()>& work, std::size_t max_answer_bytes,
                            std::size_t memory_budget_bytes) {
  IsolatedResult result;
  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0) {
    result.bytes =
        std::string("could not start the reading process (pipe: ") + std::strerror(errno) + ")";
    return result;
  }
  const pid_t pid = fork();
  if (pid < 0) {
    const int e = errno;
    ::close(fds[0]);
    ::close(fds[1]);
    result.bytes =
        std::string("could not start the reading process (fork: ") + std::strerror(e) + ")";
    return result;
  }
  if (pid == 0) {
    ::close(fds[0]);
    prctl(PR_SET_PDEATHSIG, SIGKILL);  // a parent killed (a time-out) takes the child along
    child(fds[1], work, memory_budget_bytes);
  }
  ::close(fds[1]);
  // Should the parent throw before the end (bad_alloc for the answer), the child is killed and
  // reaped and the pipe closed.
  struct Reaper {
    pid_t pid;
    int fd;
    bool armed = true;
    ~Reaper() {
      if (armed) {
        ::kill(pid, SIGKILL);
        ::close(fd);
        wait_for(pid);
      }
    }
  } reaper{pid, fds[0]};
  char header[9];
  std::uint64_t size = 0;
  bool answered = read_all(fds[0], header, sizeof header);
  if (answered) {
    std::memcpy(&size, header + 1, sizeof size);
    if (size > max_answer_bytes || (header[0] != 'A' && header[0] != 'E')) {
      result.bytes = "answered " + std::to_string(size) + " bytes, more than the " +
                     std::to_string(max_answer_bytes) + " it may";
      return result;
    }
    result.bytes.resize(size);
    answered = read_all(fds[0], result.bytes.data(), size);
  }
  reaper.armed = false;
  ::close(fds[0]);
  const int status = wait_for(pid);
  if (!answered || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    result.bytes = how_it_ended(status);
    return result;
  }
  result.outcome =
      header[0] == 'A' ? IsolatedResult::Outcome::kAnswer : IsolatedResult::Outcome::kError;
  return result;
}

}  // namespace millwatch::shell
