#pragma once
// Work done in a child process (fork), so that a library which trusts a damaged file cannot take
// the caller down with it. HDF5 1.10.8 (Debian 12) reads past its buffers when an object header's
// messages are damaged and then asks malloc for whatever length it read there (171 GB: found by
// fuzz_mat_cut_reader, tests/shell/data/damaged-v73-continuation.mat); only the child crashes or
// runs out of memory, and the caller says so. The child's address space is bounded (except under
// the sanitizers, whose shadow memory a bound would break; there a sanitizer's report in the child
// ends the child quietly instead of the process).
//
// The answer streams through a pipe as bytes: the child writes it as it goes and the parent reads
// it as it comes, each straight from and into its own objects, so that neither holds the answer
// twice (a recording of gigabytes would otherwise need twice its size on each side). The child
// returns with _exit: no destructors, atexit handlers or buffered output of the parent's state run
// twice.

#include <cstddef>
#include <functional>
#include <string>

namespace millwatch::shell {

/// The child's end of the pipe: the work writes its answer through it.
class AnswerWriter {
 public:
  explicit AnswerWriter(int fd) : fd_(fd) {}
  /// Writes n bytes; throws std::runtime_error if the parent no longer reads (it refused the
  /// answer).
  void write(const void* data, std::size_t n);
  /// Whether the answer has begun (its tag went out with the first write).
  [[nodiscard]] bool started() const { return started_; }

 private:
  int fd_;
  bool started_ = false;
};

/// The parent's end of the pipe: reads the answer, at most a given number of bytes in all.
class AnswerReader {
 public:
  AnswerReader(int fd, std::size_t max_bytes) : fd_(fd), max_(max_bytes), left_(max_bytes) {}
  /// Reads exactly n bytes; throws std::runtime_error if the answer ends before them or they
  /// would take it beyond its most.
  void read(void* data, std::size_t n);
  /// The bytes the answer may still hold (check a count against it before allocating for it).
  [[nodiscard]] std::size_t left() const { return left_; }
  /// Whether the answer ended before a read's bytes (the child closed its end: it has ended).
  [[nodiscard]] bool ended() const { return ended_; }

 private:
  int fd_;
  std::size_t max_;
  std::size_t left_;
  bool ended_ = false;
};

struct IsolatedResult {
  enum class Outcome {
    kAnswer,      ///< the work answered and `read_answer` took the whole answer
    kError,       ///< the work threw: `message` is the exception's what()
    kFailed,      ///< the child died, or its answer was cut short, too long or unreadable:
                  ///< `message` says how, e.g. "crashed (signal 11, Segmentation fault)"
    kNotStarted,  ///< no child could be started (pipe or fork failed): `message` says why
  };
  Outcome outcome = Outcome::kFailed;
  std::string message;
};

/// Runs `work` in a child process with at most `memory_budget_bytes` more address space than the
/// caller has now; `work` writes its answer with the AnswerWriter (an error it throws after its
/// first write cuts the answer short: kFailed, "its answer broke off: " and the error's text, up
/// to PIPE_BUF bytes of it). In the caller,
/// `read_answer` reads the answer as it comes, at most `max_answer_bytes` of it; whatever it
/// throws (std::exception) makes the outcome kFailed, and the child is killed. Blocks until the
/// child has answered and exited. Call it with no other thread inside the library the work uses
/// (the child holds a copy of its state as it is at the fork).
IsolatedResult run_isolated(const std::function<void(AnswerWriter&)>& work,
                            const std::function<void(AnswerReader&)>& read_answer,
                            std::size_t max_answer_bytes, std::size_t memory_budget_bytes);

}  // namespace millwatch::shell
