// shell::run_isolated: the work's answer streamed, its error, its crash before or during its
// answer, its running out of memory, an answer shorter or longer than its reader takes or than
// allowed, the reader's own error and no child at all, each as the caller sees it — and the
// caller still running.

#include "shell/isolated_call.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstddef>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#if defined(__SANITIZE_ADDRESS__)
#define MILLWATCH_TEST_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define MILLWATCH_TEST_SANITIZED 1
#endif
#endif

namespace millwatch::shell {
namespace {

constexpr std::size_t kMiB = std::size_t{1} << 20;

/// A work that writes `bytes` in pieces of 1, 2, 3 … 4096 bytes.
std::function<void(AnswerWriter&)> writes(const std::string& bytes) {
  return [&bytes](AnswerWriter& out) {
    for (std::size_t at = 0, piece = 1; at < bytes.size(); at += piece, piece = piece % 4096 + 1) {
      out.write(bytes.data() + at, std::min(piece, bytes.size() - at));
    }
  };
}

/// A reader that takes `n` bytes into `into`, 4000 at a time.
std::function<void(AnswerReader&)> reads(std::size_t n, std::string& into) {
  return [n, &into](AnswerReader& in) {
    into.resize(n);
    for (std::size_t at = 0; at < n; at += 4000) {
      in.read(into.data() + at, std::min<std::size_t>(4000, n - at));
    }
  };
}

TEST(IsolatedCall, TheAnswerStreamsBackByteForByte) {
  std::string expected(3 * kMiB, '\0');  // more than a pipe holds: the parent reads as it comes
  for (std::size_t i = 0; i < expected.size(); ++i) {
    expected[i] = static_cast<char>(i * 7919 % 251);
  }
  std::string got;
  const IsolatedResult r =
      run_isolated(writes(expected), reads(expected.size(), got), 4 * kMiB, 256 * kMiB);
  ASSERT_EQ(r.outcome, IsolatedResult::Outcome::kAnswer) << r.message;
  EXPECT_TRUE(r.message.empty());
  EXPECT_EQ(got, expected);
}

TEST(IsolatedCall, AnEmptyAnswerIsAnAnswer) {
  bool read = false;
  const IsolatedResult r =
      run_isolated([](AnswerWriter&) {}, [&](AnswerReader&) { read = true; }, kMiB, 256 * kMiB);
  EXPECT_EQ(r.outcome, IsolatedResult::Outcome::kAnswer) << r.message;
  EXPECT_TRUE(read);
}

TEST(IsolatedCall, AnExceptionIsTheErrorWithItsText) {
  bool read = false;
  const IsolatedResult r =
      run_isolated([](AnswerWriter&) { throw std::runtime_error("x.mat: no variable \"fx\""); },
                   [&](AnswerReader&) { read = true; }, kMiB, 256 * kMiB);
  EXPECT_EQ(r.outcome, IsolatedResult::Outcome::kError);
  EXPECT_EQ(r.message, "x.mat: no variable \"fx\"");
  EXPECT_FALSE(read);
}

TEST(IsolatedCall, AChildThatDiesIsSaidWithItsSignal) {
  const IsolatedResult r = run_isolated(
      [](AnswerWriter&) {
        std::raise(SIGKILL);  // as the kernel ends a process; no handler can intervene
      },
      [](AnswerReader&) {}, kMiB, 256 * kMiB);
  EXPECT_EQ(r.outcome, IsolatedResult::Outcome::kFailed);
  EXPECT_EQ(r.message, "crashed (signal 9, Killed)");
}

TEST(IsolatedCall, AChildThatDiesMidAnswerIsSaidWithItsSignal) {
  std::string got;
  const IsolatedResult r = run_isolated(
      [](AnswerWriter& out) {
        const std::string half(kMiB, 'x');
        out.write(half.data(), half.size());
        std::raise(SIGTERM);
      },
      reads(2 * kMiB, got), 4 * kMiB, 256 * kMiB);
  EXPECT_EQ(r.outcome, IsolatedResult::Outcome::kFailed);
  EXPECT_EQ(r.message, "crashed (signal 15, Terminated)");
}

// The kernel's out-of-memory killer ends a process with SIGKILL, as the parent ends a child whose
// answer it refuses: a child killed mid-answer by another is said so, not as an answer cut short.
TEST(IsolatedCall, AChildKilledMidAnswerIsSaidKilledNotCutShort) {
  std::string got;
  const IsolatedResult r = run_isolated(
      [](AnswerWriter& out) {
        const std::string half(kMiB, 'x');
        out.write(half.data(), half.size());
        std::raise(SIGKILL);
      },
      reads(2 * kMiB, got), 4 * kMiB, 256 * kMiB);
  EXPECT_EQ(r.outcome, IsolatedResult::Outcome::kFailed);
  EXPECT_EQ(r.message, "crashed (signal 9, Killed)");
}

// An error after the answer began cuts it short, and its text still reaches the caller.
TEST(IsolatedCall, AnErrorAfterTheAnswerBeganIsSaidWithItsText) {
  std::string got;
  const IsolatedResult r = run_isolated(
      [](AnswerWriter& out) {
        const std::string part(3 * kMiB, 'x');  // more than the pipe holds: the parent reads it
        out.write(part.data(), part.size());
        throw std::runtime_error("x.mat: the dataset fy ends at row 12");
      },
      reads(4 * kMiB, got), 8 * kMiB, 256 * kMiB);
  EXPECT_EQ(r.outcome, IsolatedResult::Outcome::kFailed);
  EXPECT_EQ(r.message, "its answer broke off: x.mat: the dataset fy ends at row 12");
}

// An error thrown once the reader has taken all it wanted: the answer is not whole (the work
// did not finish it), and the error says why.
TEST(IsolatedCall, AnErrorAfterAllTheReaderTookIsSaidWithItsText) {
  const std::string ten(10, 'x');
  std::string got;
  const IsolatedResult r = run_isolated(
      [&](AnswerWriter& out) {
        out.write(ten.data(), ten.size());
        throw std::runtime_error("x.mat: the time vector is not increasing");
      },
      reads(ten.size(), got), kMiB, 256 * kMiB);
  EXPECT_EQ(r.outcome, IsolatedResult::Outcome::kFailed);
  EXPECT_EQ(r.message, "its answer broke off: x.mat: the time vector is not increasing");
}

// A caller that ignores SIGCHLD (inherited across exec) has its children reaped by the kernel:
// waitpid cannot say how they ended. What they sent is taken at its word; a child that sent
// nothing is said to have ended, how not known.
TEST(IsolatedCall, WithSigchldIgnoredAnAnswerOrAnErrorStillCounts) {
  struct sigaction ignore {};
  ignore.sa_handler = SIG_IGN;
  struct sigaction before {};
  ASSERT_EQ(sigaction(SIGCHLD, &ignore, &before), 0);
  const std::string hundred(100, 'y');
  std::string got;
  const IsolatedResult answer =
      run_isolated(writes(hundred), reads(hundred.size(), got), kMiB, 256 * kMiB);
  const IsolatedResult error =
      run_isolated([](AnswerWriter&) { throw std::runtime_error("x.mat: no variable fx"); },
                   [](AnswerReader&) {}, kMiB, 256 * kMiB);
  const IsolatedResult crash = run_isolated([](AnswerWriter&) { std::raise(SIGKILL); },
                                            [](AnswerReader&) {}, kMiB, 256 * kMiB);
  sigaction(SIGCHLD, &before, nullptr);
  EXPECT_EQ(answer.outcome, IsolatedResult::Outcome::kAnswer) << answer.message;
  EXPECT_EQ(got, hundred);
  EXPECT_EQ(error.outcome, IsolatedResult::Outcome::kError) << error.message;
  EXPECT_EQ(error.message, "x.mat: no variable fx");
  EXPECT_EQ(crash.outcome, IsolatedResult::Outcome::kFailed);
  EXPECT_EQ(crash.message, "ended, how is not known (it could not be waited for)");
}

// Something thrown that is no std::exception is an error too, not a crash.
TEST(IsolatedCall, AThrowOfNoStandardTypeIsAnError) {
  const IsolatedResult r =
      run_isolated([](AnswerWriter&) { throw 42; }, [](AnswerReader&) {}, kMiB, 256 * kMiB);
  EXPECT_EQ(r.outcome, IsolatedResult::Outcome::kError);
  EXPECT_EQ(r.message, "an exception of no standard type");
}

TEST(IsolatedCall, AnAnswerShorterThanItsReaderTakesIsCutShort) {
  const std::string ten(10, 'x');
  std::string got;
  const IsolatedResult r = run_isolated(writes(ten), reads(20, got), kMiB, 256 * kMiB);
  EXPECT_EQ(r.outcome, IsolatedResult::Outcome::kFailed);
  EXPECT_EQ(r.message, "its answer ends early");
}

TEST(IsolatedCall, AnAnswerLongerThanItsReaderTakesIsRefused) {
  const std::string hundred(100, 'x');
  std::string got;
  const IsolatedResult r = run_isolated(writes(hundred), reads(50, got), kMiB, 256 * kMiB);
  EXPECT_EQ(r.outcome, IsolatedResult::Outcome::kFailed);
  EXPECT_EQ(r.message, "answered more than its reader takes");
}

TEST(IsolatedCall, AnAnswerLongerThanAllowedIsRefused) {
  const std::string two(2 * kMiB, 'x');  // the child blocks on the full pipe until it is killed
  std::string got;
  const IsolatedResult r = run_isolated(writes(two), reads(two.size(), got), kMiB, 256 * kMiB);
  EXPECT_EQ(r.outcome, IsolatedResult::Outcome::kFailed);
  EXPECT_EQ(r.message, "answered more than the 1048576 bytes it may");
}

TEST(IsolatedCall, TheReadersErrorEndsTheChild) {
  const std::string two(2 * kMiB, 'x');
  const IsolatedResult r = run_isolated(
      writes(two),
      [](AnswerReader& in) {
        char first = 0;
        in.read(&first, 1);
        throw std::runtime_error("the answer states 10^12 samples");
      },
      4 * kMiB, 256 * kMiB);
  EXPECT_EQ(r.outcome, IsolatedResult::Outcome::kFailed);
  EXPECT_EQ(r.message, "the answer states 10^12 samples");
}

TEST(IsolatedCall, NoPipeIsNotStartedNotAFailedChild) {
  // No descriptor free: pipe2 fails with EMFILE (a bound root is held to as well).
  rlimit before{};
  ASSERT_EQ(getrlimit(RLIMIT_NOFILE, &before), 0);
  const int lowest_free = ::dup(0);
  ASSERT_GE(lowest_free, 0);
  ::close(lowest_free);
  rlimit tight = before;
  tight.rlim_cur = static_cast<rlim_t>(lowest_free);
  ASSERT_EQ(setrlimit(RLIMIT_NOFILE, &tight), 0);
  bool ran = false;
  const IsolatedResult r =
      run_isolated([&](AnswerWriter&) { ran = true; }, [](AnswerReader&) {}, kMiB, 256 * kMiB);
  ASSERT_EQ(setrlimit(RLIMIT_NOFILE, &before), 0);
  EXPECT_EQ(r.outcome, IsolatedResult::Outcome::kNotStarted);
  EXPECT_EQ(r.message, "pipe: Too many open files");
  EXPECT_FALSE(ran);
}

TEST(IsolatedCall, TheChildsAddressSpaceIsBounded) {
#ifdef MILLWATCH_TEST_SANITIZED
  GTEST_SKIP() << "not bounded under the sanitizers (their shadow memory needs the address space)";
#else
  // 4 GiB asked for with a budget of 256 MiB: refused (bad_alloc) in the child, not attempted.
  const IsolatedResult r = run_isolated(
      [](AnswerWriter& out) {
        std::vector<char> big(4096 * kMiB);
        out.write(&big[big.size() / 2], 1);
      },
      [](AnswerReader&) {}, kMiB, 256 * kMiB);
  EXPECT_EQ(r.outcome, IsolatedResult::Outcome::kError);
  EXPECT_EQ(r.message,
            "out of memory (the reading process may map 256 MiB beyond what it started with)");
#endif
}

}  // namespace
}  // namespace millwatch::shell
