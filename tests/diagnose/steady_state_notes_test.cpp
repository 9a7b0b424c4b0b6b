// What the diagnosis says of its final model's steady state laid along the record
// (Diagnosis::final_notes): which of the record's revolutions replay a cycle cut at
// model::kMaxCycleRevolutions, counted from where the record starts in the cycle, and slots
// that never settled. Counted by hand for a cycle of 64 revolutions.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/diagnose/diagnosis.hpp"

namespace millwatch::diagnose {
namespace {

TEST(SteadyStateNotes, RevolutionsRoundAgainCountFromWhereTheRecordStartsInTheCycle) {
  // From the cycle's start: the 20 revolutions after its 64.
  EXPECT_DOUBLE_EQ(revolutions_round_again(0.0, 84.0, 64), 20.0);
  // From its revolution 30.5: the cycle wraps after 33.5 revolutions.
  EXPECT_DOUBLE_EQ(revolutions_round_again(30.5, 84.0, 64), 50.5);
  // A record shorter than the cycle wraps too when it starts late in it ...
  EXPECT_DOUBLE_EQ(revolutions_round_again(60.0, 10.0, 64), 6.0);
  // ... and not when it ends before the cycle's end.
  EXPECT_DOUBLE_EQ(revolutions_round_again(10.0, 54.0, 64), 0.0);
  EXPECT_DOUBLE_EQ(revolutions_round_again(0.0, 40.0, 64), 0.0);
}

TEST(SteadyStateNotes, SayWhatOfTheFinalModelIsNotItsOwnRevolutionByRevolution) {
  EXPECT_TRUE(steady_state_notes(0.0, 0, 3600).empty());
  EXPECT_TRUE(steady_state_notes(0.7, 0, 3600).empty());  // no whole revolution round again
  const std::vector<std::string> both = steady_state_notes(20.4, 13, 3600);
  ASSERT_EQ(both.size(), 2U);
  EXPECT_NE(both[0].find("outgrew 64 revolutions: 20 revolutions of the record are compared with "
                         "its first 64 played round again"),
            std::string::npos)
      << both[0];
  EXPECT_NE(both[1].find("13 of the final model's 3600 slots (disc, immersion) did not repeat "
                         "within 600 revolutions"),
            std::string::npos)
      << both[1];
  const std::vector<std::string> slots_only = steady_state_notes(0.0, 2, 7200);
  ASSERT_EQ(slots_only.size(), 1U);
  EXPECT_NE(slots_only[0].find("2 of the final model's 7200 slots"), std::string::npos);
}

}  // namespace
}  // namespace millwatch::diagnose
