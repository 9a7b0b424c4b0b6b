// shell::unique_stems: one output name per input, told apart where two inputs share a stem, and
// with no control character (a line break in a folder's name would break the scripts that plot
// into it).

#include "shell/output_file.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace millwatch::shell {
namespace {

TEST(UniqueStems, SharedStemsAreNumberedAndControlCharactersReplaced) {
  const std::vector<std::string> stems =
      unique_stems({"a/cut1.csv", "b/cut1.mat", "cut\n!rm x\t.csv", "cut2.lcm"});
  EXPECT_EQ(stems, (std::vector<std::string>{"cut1", "cut1_2", "cut_!rm x_", "cut2"}));
}

}  // namespace
}  // namespace millwatch::shell
