#pragma once
// Work done in a child process (fork), so that a library which trusts a damaged file cannot take
// the caller down with it. HDF5 1.10.8 (Debian 12) reads past its buffers when an object header's
// messages are damaged and then asks malloc for whatever length it read there (171 GB: found by
// fuzz_mat_cut_reader, tests/shell/data/damaged-v73-continuation.mat); only the child crashes or
// runs out of memory, and the caller says so. The child's address space is bounded (except under
// the sanitizers, whose shadow memory a bound would break; there a sanitizer's report in the child
// ends the child quietly instead of the process).
//
// The answer comes back through a pipe as bytes: the caller encodes and decodes it. The child
// returns with _exit: no destructors, atexit handlers or buffered output of the parent's state run
// twice.

#include <cstddef>
#include <functional>
#include <string>

namespace millwatch::shell {

struct IsolatedResult {
  enum class Outcome {
    kAnswer,  ///< `bytes` is what the work returned
    kError,   ///< the work threw: `bytes` is the exception's what()
    kFailed,  ///< the child died or answered too much: `bytes` says how, e.g. "crashed (signal
              ///< 11, Segmentation fault)"
  };
  Outcome outcome = Outcome::kFailed;
  std::string bytes;
};

/// Runs `work` in a child process with at most `memory_budget_bytes` more address space than the
/// caller has now. An answer longer than `max_answer_bytes` is kFailed (the child is killed).
/// Blocks until the child has answered and exited. Call it with no other thread inside the
/// library the work uses (the child holds a copy of its state as it is at the fork).
IsolatedResult run_isolated(const std::function<std::string()>& work, std::size_t max_answer_bytes,
                            std::size_t memory_budget_bytes);

}  // namespace millwatch::shell
