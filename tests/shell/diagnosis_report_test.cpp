// The report's estimates can be read to their uncertainty: the value is written to its σ's
// second significant digit, not rounded to four digits whatever σ says.

#include "shell/diagnosis_report.hpp"

#include <gtest/gtest.h>

namespace millwatch::shell {
namespace {

TEST(DiagnosisReport, AValueIsWrittenToItsSigma) {
  EXPECT_EQ(value_sigma(24749.998, 0.001), "24749.998 ± 0.001");
  EXPECT_EQ(value_sigma(10421.99, 0.0013), "10421.99 ± 0.0013");
  EXPECT_EQ(value_sigma(1.8234, 0.021), "1.823 ± 0.021");  // at least 4 digits
  EXPECT_EQ(value_sigma(0.000123456, 1.2e-7), "0.00012346 ± 1.2e-07");
  EXPECT_EQ(value_sigma(1000.7, 5.1), "1000.7 ± 5.1");
  EXPECT_EQ(value_sigma(3.5, 0.0), "3.5");  // no σ: the value alone
}

}  // namespace
}  // namespace millwatch::shell
