// The replay's progress line: its speed never rounds to "0×" and, once the recording is read,
// it says the replay is finishing rather than "0 s left" (on a short record with identification
// the line had read "100.0 % … (0× real time), 0 s left" for the five seconds of the last fits).

#include "shell/progress_line.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace millwatch::shell {
namespace {

TEST(ProgressLine, TimesRealTimeKeepsTwoDigitsBelowTen) {
  EXPECT_EQ(times_real_time(1234.4), "1234");
  EXPECT_EQ(times_real_time(35.2), "35");
  EXPECT_EQ(times_real_time(9.96), "10");
  EXPECT_EQ(times_real_time(2.04), "2.0");
  EXPECT_EQ(times_real_time(0.5), "0.5");
  EXPECT_EQ(times_real_time(0.02), "0.02");
  EXPECT_EQ(times_real_time(0.0234), "0.023");
  EXPECT_EQ(times_real_time(0.0), "<0.001");  // never "0"
  EXPECT_EQ(times_real_time(std::numeric_limits<double>::quiet_NaN()), "—");
  EXPECT_EQ(times_real_time(std::numeric_limits<double>::infinity()), "—");
}

TEST(ProgressLine, ReplayLineSaysTimeLeftThenFinishing) {
  EXPECT_EQ(replay_progress_text(0.42, 4.2, 2.1, true),
            " 42.0 %  4.2 s of recording in 2.1 s (2.0× real time), 3 s left");
  // Too early to say how long is left.
  EXPECT_EQ(replay_progress_text(0.005, 0.05, 2.0, false),
            "  0.5 %  0.1 s of recording in 2.0 s (0.025× real time)");
  EXPECT_EQ(replay_progress_text(1.0, 0.1, 5.0, true),
            "100.0 %  0.1 s of recording in 5.0 s (0.02× real time), finishing "
            "(identification's last fits)");
  EXPECT_EQ(replay_progress_text(1.0, 10.0, 0.5, false),
            "100.0 %  10.0 s of recording in 0.5 s (20× real time), finishing");
}

}  // namespace
}  // namespace millwatch::shell
