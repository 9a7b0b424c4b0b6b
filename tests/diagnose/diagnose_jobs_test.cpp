// The diagnosis on several threads (DiagnoseOptions::jobs): the candidates of a round, h_min's
// profile and the golden section's pairs are fitted at once, each on an engine of its own, and
// the result is the one thread's, to the last bit. The cut hides [001]'s ploughed-area law, so
// that h_min is profiled inside a candidate's fit (on that candidate's thread), refined at its
// step and profiled again in the final model (both on every thread).

#include <gtest/gtest.h>

#include <algorithm>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/diagnose/diagnosis.hpp"
#include "core/diagnose/diagnosis_json.hpp"
#include "tests/support/hidden_effect_cut.hpp"

namespace millwatch::diagnose {
namespace {

struct Diagnosed {
  Diagnosis diagnosis;
  std::vector<std::string> progress;
};

Diagnosed diagnose_on(const test::HiddenEffectCut& cut, int jobs) {
  Diagnosed run;
  std::mutex m;  // diagnose() calls progress from one thread at a time; the test checks it
  DiagnoseOptions o;
  o.jobs = jobs;
  o.progress = [&](std::string_view line) {
    const std::unique_lock lock(m, std::try_to_lock);
    EXPECT_TRUE(lock.owns_lock()) << "progress called from two threads at once: " << line;
    run.progress.emplace_back(line);
  };
  run.diagnosis = diagnose(cut.record, cut.start, o);
  return run;
}

TEST(DiagnoseJobs, ThreeThreadsGiveTheOneThreadsDiagnosis) {
  const auto cut = test::hidden_effect_cut({"ploughing_area"});
  const Diagnosed one = diagnose_on(cut, 1);
  const Diagnosed three = diagnose_on(cut, 3);
  ASSERT_TRUE(one.diagnosis.ok) << one.diagnosis.message;
  ASSERT_TRUE(three.diagnosis.ok) << three.diagnosis.message;
  // The search found what the cut hides (so the comparison below is of a real diagnosis).
  EXPECT_EQ(one.diagnosis.named_effects, std::vector<std::string>{"ploughing_area"})
      << one.diagnosis.verdict;
  // Everything the report says, every round's scores included, but the time it took.
  auto a = to_json(one.diagnosis);
  auto b = to_json(three.diagnosis);
  a.erase("seconds");
  b.erase("seconds");
  EXPECT_EQ(a.dump(), b.dump());
  // Every candidate of every round was announced, on either count of threads.
  EXPECT_EQ(one.progress.size(), three.progress.size());
  auto sorted = [](std::vector<std::string> v) {
    std::sort(v.begin(), v.end());
    return v;
  };
  EXPECT_EQ(sorted(one.progress), sorted(three.progress));
}

TEST(DiagnoseJobs, ANegativeCountIsRefusedNamingIt) {
  const auto cut = test::hidden_effect_cut({});
  DiagnoseOptions o;
  o.jobs = -2;
  try {
    (void)diagnose(cut.record, cut.start, o);
    ADD_FAILURE() << "jobs -2 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("jobs"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("-2"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace millwatch::diagnose
