// shell::run_isolated: the work's answer, its error, its crash, its running out of memory and an
// answer longer than allowed, each as the caller sees it — and the caller still running.

#include "shell/isolated_call.hpp"

#include <gtest/gtest.h>

#include <csignal>
#include <cstddef>
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

TEST(IsolatedCall, TheAnswerComesBackByteForByte) {
  std::string expected(3 * kMiB, '\0');  // more than a pipe holds: the parent reads as it comes
  for (std::size_t i = 0; i < expected.size(); ++i) {
    expected[i] = static_cast<char>(i * 7919 % 251);
  }
  const IsolatedResult r = run_isolated([&] { return expected; }, 4 * kMiB, 256 * kMiB);
  ASSERT_EQ(r.outcome, IsolatedResult::Outcome::kAnswer) << r.bytes;
  EXPECT_EQ(r.bytes, expected);
}

TEST(IsolatedCall, AnExceptionIsTheErrorWithItsText) {
  const IsolatedResult r =
      run_isolated([]() -> std::string { throw std::runtime_error("x.mat: no variable \"fx\""); },
                   kMiB, 256 * kMiB);
  EXPECT_EQ(r.outcome, IsolatedResult::Outcome::kError);
  EXPECT_EQ(r.bytes, "x.mat: no variable \"fx\"");
}

TEST(IsolatedCall, AChildThatDiesIsSaidWithItsSignal) {
  const IsolatedResult r = run_isolated(
      []() -> std::string {
        std::raise(SIGKILL);  // as the kernel ends a process; no handler can intervene
        return "never";
      },
      kMiB, 256 * kMiB);
  EXPECT_EQ(r.outcome, IsolatedResult::Outcome::kFailed);
  EXPECT_EQ(r.bytes, "crashed (signal 9, Killed)");
}

TEST(IsolatedCall, AnAnswerLongerThanAllowedIsRefused) {
  const IsolatedResult r =
      run_isolated([] { return std::string(2 * kMiB, 'x'); }, kMiB, 256 * kMiB);
  EXPECT_EQ(r.outcome, IsolatedResult::Outcome::kFailed);
  EXPECT_EQ(r.bytes, "answered 2097152 bytes, more than the 1048576 it may");
}

TEST(IsolatedCall, TheChildsAddressSpaceIsBounded) {
#ifdef MILLWATCH_TEST_SANITIZED
  GTEST_SKIP() << "not bounded under the sanitizers (their shadow memory needs the address space)";
#else
  // 4 GiB asked for with a budget of 256 MiB: refused (bad_alloc) in the child, not attempted.
  const IsolatedResult r = run_isolated(
      [] {
        std::vector<char> big(4096 * kMiB);
        return std::string(1, big[big.size() / 2]);
      },
      kMiB, 256 * kMiB);
  EXPECT_EQ(r.outcome, IsolatedResult::Outcome::kError);
  EXPECT_EQ(r.bytes,
            "out of memory (the reading process may map 256 MiB beyond what it started with)");
#endif
}

}  // namespace
}  // namespace millwatch::shell
