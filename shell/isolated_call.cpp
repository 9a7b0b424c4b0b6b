#include "shell/isolated_call.hpp"

#include <fcntl.h>
#include <limits.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstdint>
#include <cstring>
#include <exception>
#include <fstream>
#include <new>
#include <stdexcept>
#include <string>

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
/// The longest text of an error after the answer began (within one atomic pipe write, so that
/// the child never blocks on it).
constexpr std::size_t kMaxLateErrorBytes = PIPE_BUF;

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

/// The longest error text the child sends (the rest is cut).
constexpr std::size_t kMaxErrorBytes = 65536;

/// The work's error, tagged: 'E', its length and its text.
bool send_error(int fd, std::string text) {
  text.resize(std::min(text.size(), kMaxErrorBytes));
  const std::uint64_t size = text.size();
  char header[1 + sizeof size];
  header[0] = 'E';
  std::memcpy(header + 1, &size, sizeof size);
  return write_all(fd, header, sizeof header) && write_all(fd, text.data(), text.size());
}

[[noreturn]] void child(int fd, int late_error_fd, const std::function<void(AnswerWriter&)>& work,
                        std::size_t budget_bytes) {
  bound_child(budget_bytes);
  AnswerWriter out(fd);
  std::string error;
  try {
    work(out);
    out.write(nullptr, 0);  // an empty answer's tag
    _exit(0);
  } catch (const std::bad_alloc&) {
    error = "out of memory (the reading process may map " + std::to_string(budget_bytes >> 20) +
            " MiB beyond what it started with)";
  } catch (const std::exception& e) {
    error = e.what();
  } catch (...) {
    error = "an exception of no standard type";
  }
  if (!out.started()) {
    _exit(send_error(fd, std::move(error)) ? 0 : 1);
  }
  // After the answer's first bytes an error cuts it short: its text goes by the other pipe.
  error.resize(std::min(error.size(), kMaxLateErrorBytes));
  (void)!::write(late_error_fd, error.data(), error.size());
  _exit(1);
}

/// How the child ended, as waitpid told, if it could wait for it (not with SIGCHLD ignored: the
/// kernel reaps the child then, and waitpid fails with ECHILD).
struct End {
  bool waited = false;
  int status = 0;
};

std::string how_it_ended(End end) {
  if (!end.waited) {
    return "ended, how is not known (it could not be waited for)";
  }
  const int status = end.status;
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

End wait_for(pid_t pid) {
  End end;
  while (waitpid(pid, &end.status, 0) < 0) {
    if (errno != EINTR) {
      return {};
    }
  }
  end.waited = true;
  return end;
}

/// The child and the parent's ends of its pipes (the answer, an error after the answer began),
/// until finish(); killed, closed and reaped on any other way out (a throw such as bad_alloc).
class Child {
 public:
  Child(pid_t pid, int fd, int late_error_fd) : pid_(pid), fd_(fd), late_error_fd_(late_error_fd) {}
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;
  ~Child() {
    if (pid_ > 0) {
      finish(true);
    }
  }
  [[nodiscard]] int fd() const { return fd_; }
  /// Kills the child if asked, closes the pipe and returns the child's wait status. (Killed
  /// first: a pipe closed under a child still writing would end it with SIGPIPE, which would
  /// read as a crash of its own.)
  End finish(bool kill) {
    if (kill) {
      ::kill(pid_, SIGKILL);  // no effect on a child that has already ended: its status stays
    }
    ::close(fd_);
    const End end = wait_for(pid_);
    pid_ = -1;
    late_error_ = read_late_error();
    ::close(late_error_fd_);
    return end;
  }
  /// After finish(): the text of an error the work threw after its answer began ("" if none).
  [[nodiscard]] const std::string& late_error() const { return late_error_; }

 private:
  /// The child has ended: its end of the pipe is closed, and what it wrote is there whole.
  std::string read_late_error() const {
    std::string text(kMaxLateErrorBytes, '\0');
    ssize_t n = 0;
    do {
      n = ::read(late_error_fd_, text.data(), text.size());
    } while (n < 0 && errno == EINTR);
    text.resize(n > 0 ? static_cast<std::size_t>(n) : 0);
    return text;
  }

  pid_t pid_;
  int fd_;
  int late_error_fd_;
  std::string late_error_;
};

/// Whether the child ended by itself other than with an answer: what went wrong is then its end
/// (a crash mid-answer), not the answer the parent was left with. (Not known unless waited for.)
bool ended_badly(End end) {
  return end.waited && ((WIFSIGNALED(end.status) && WTERMSIG(end.status) != SIGKILL) ||
                        (WIFEXITED(end.status) && WEXITSTATUS(end.status) != 0));
}

/// Whether the child exited (of itself), as far as known: a child not waited for is taken at
/// what it sent.
bool exited(End end) {
  return !end.waited || WIFEXITED(end.status);
}

IsolatedResult failed(std::string message) {
  return {IsolatedResult::Outcome::kFailed, std::move(message)};
}

/// The parent's side after the child's tag 'A': the answer, the pipe's end, the child's exit.
IsolatedResult take_answer(Child& child, const std::function<void(AnswerReader&)>& read_answer,
                           std::size_t max_answer_bytes) {
  std::string problem;
  AnswerReader in(child.fd(), max_answer_bytes);
  try {
    read_answer(in);
    char extra = 0;
    if (read_all(child.fd(), &extra, 1)) {
      problem = "answered more than its reader takes";
    }
  } catch (const std::bad_alloc&) {
    problem = "answered more than this process has memory for";
  } catch (const std::exception& e) {
    problem = e.what();
  }
  // An answer that ended early: the child has ended (or is ending) by itself, not to be killed,
  // so that how it ended (the kernel's SIGKILL when out of memory, an error) is its own.
  const bool ended = in.ended();
  const End end = child.finish(!problem.empty() && !ended);
  if (!child.late_error().empty()) {  // also after all the reader took: the work did not finish
    return failed("its answer broke off: " + child.late_error());
  }
  if (ended_badly(end) || ((problem.empty() || ended) && !exited(end))) {
    return failed(how_it_ended(end));
  }
  if (!problem.empty()) {
    return failed(problem);
  }
  return {IsolatedResult::Outcome::kAnswer, {}};
}

/// The parent's side after the child's tag 'E': the error's text and the child's exit.
IsolatedResult take_error(Child& child) {
  std::uint64_t size = 0;
  std::string text;
  bool whole =
      read_all(child.fd(), reinterpret_cast<char*>(&size), sizeof size) && size <= kMaxErrorBytes;
  if (whole) {
    text.resize(size);
    whole = read_all(child.fd(), text.data(), text.size());
  }
  const bool too_long = size > kMaxErrorBytes;
  const End end = child.finish(!whole);
  if (too_long) {
    return failed("its error states " + std::to_string(size) + " bytes, more than the " +
                  std::to_string(kMaxErrorBytes) + " it may");
  }
  if (!whole || !exited(end) || ended_badly(end)) {
    return failed(how_it_ended(end));
  }
  return {IsolatedResult::Outcome::kError, std::move(text)};
}

}  // namespace

void AnswerWriter::write(const void* data, std::size_t n) {
  if (!started_) {
    const char tag = 'A';
    if (!write_all(fd_, &tag, 1)) {
      throw std::runtime_error("the answer's reader is gone");
    }
    started_ = true;
  }
  if (!write_all(fd_, static_cast<const char*>(data), n)) {
    throw std::runtime_error("the answer's reader is gone");
  }
}

void AnswerReader::read(void* data, std::size_t n) {
  if (n > left_) {
    throw std::runtime_error("answered more than the " + std::to_string(max_) + " bytes it may");
  }
  if (!read_all(fd_, static_cast<char*>(data), n)) {
    ended_ = true;
    throw std::runtime_error("its answer ends early");
  }
  left_ -= n;
}

IsolatedResult run_isolated(const std::function<void(AnswerWriter&)>& work,
                            const std::function<void(AnswerReader&)>& read_answer,
                            std::size_t max_answer_bytes, std::size_t memory_budget_bytes) {
  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0) {
    return {IsolatedResult::Outcome::kNotStarted, std::string("pipe: ") + std::strerror(errno)};
  }
  int late[2];  // the late error's: read only once the child has ended
  if (pipe2(late, O_CLOEXEC | O_NONBLOCK) != 0) {
    const int e = errno;
    ::close(fds[0]);
    ::close(fds[1]);
    return {IsolatedResult::Outcome::kNotStarted, std::string("pipe: ") + std::strerror(e)};
  }
  const pid_t parent = ::getpid();
  const pid_t pid = fork();
  if (pid < 0) {
    const int e = errno;
    for (const int fd : {fds[0], fds[1], late[0], late[1]}) {
      ::close(fd);
    }
    return {IsolatedResult::Outcome::kNotStarted, std::string("fork: ") + std::strerror(e)};
  }
  if (pid == 0) {
    ::close(fds[0]);
    ::close(late[0]);
    prctl(PR_SET_PDEATHSIG, SIGKILL);  // a parent killed (a time-out) takes the child along
    if (::getppid() != parent) {
      _exit(1);  // it died before the line above: nobody would read the answer
    }
    child(fds[1], late[1], work, memory_budget_bytes);
  }
  ::close(fds[1]);
  ::close(late[1]);
  Child c(pid, fds[0], late[0]);
  char tag = 0;
  if (!read_all(c.fd(), &tag, 1)) {
    return failed(how_it_ended(c.finish(false)));
  }
  switch (tag) {
    case 'A':
      return take_answer(c, read_answer, max_answer_bytes);
    case 'E':
      return take_error(c);
    default:
      c.finish(true);
      return failed("its answer is not one it can give");
  }
}

}  // namespace millwatch::shell
