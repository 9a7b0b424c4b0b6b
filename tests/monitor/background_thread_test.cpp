// monitor::make_this_thread_batch: the thread that calls it is SCHED_BATCH work, and the
// threads that do background work beside the sample thread — the model builder's,
// identification's worker — are, while the caller's own thread keeps its policy.

#include "core/monitor/background_thread.hpp"

#include <gtest/gtest.h>
#include <sched.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <thread>

#include "core/identify/identifier.hpp"
#include "core/model/model_config.hpp"
#include "core/monitor/model_builder.hpp"
#include "core/signal/butterworth_lowpass.hpp"

namespace millwatch::monitor {
namespace {

/// This process's threads in SCHED_BATCH (/proc/self/task/*/stat: the policy is field 41).
int batch_threads() {
  int n = 0;
  for (const auto& task : std::filesystem::directory_iterator("/proc/self/task")) {
    std::ifstream in(task.path() / "stat");
    std::string stat((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    // Fields after the command's closing parenthesis start at field 3.
    std::istringstream fields(stat.substr(stat.rfind(')') + 2));
    std::string field;
    for (int k = 3; k <= 41 && (fields >> field); ++k) {
    }
    n += field == std::to_string(SCHED_BATCH) ? 1 : 0;
  }
  return n;
}

/// Waits up to 5 s for `want` batch threads (a thread marks itself as it starts).
int wait_for_batch_threads(int want) {
  int n = batch_threads();
  for (int i = 0; i < 500 && n < want; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    n = batch_threads();
  }
  return n;
}

TEST(BackgroundThread, TheCallingThreadBecomesBatchWorkAndNoOtherDoes) {
  const int caller_policy = sched_getscheduler(0);
  int policy = -1;
  bool made = false;
  std::thread t([&] {
    made = make_this_thread_batch();
    policy = sched_getscheduler(0);
  });
  t.join();
  EXPECT_TRUE(made);
  EXPECT_EQ(policy, SCHED_BATCH);
  EXPECT_EQ(sched_getscheduler(0), caller_policy);
}

TEST(BackgroundThread, TheModelBuilderAndIdentificationWorkAsBatch) {
  ASSERT_EQ(batch_threads(), 0);
  const auto filter = signal::ButterworthDesign::lowpass(50000.0, 3300.0, 4);
  const model::ModelConfig model;
  {
    ModelBuilder builder(model, filter, false);
    EXPECT_EQ(wait_for_batch_threads(1), 1);
    identify::Identifier id(
        model, [filter](double hz) { return filter.response(hz); }, identify::FitOptions{},
        nullptr);
    EXPECT_EQ(wait_for_batch_threads(2), 2);
  }
  EXPECT_EQ(batch_threads(), 0);  // both joined
  EXPECT_NE(sched_getscheduler(0), SCHED_BATCH);
}

}  // namespace
}  // namespace millwatch::monitor
