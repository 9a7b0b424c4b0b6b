// The report's estimates can be read to their uncertainty: the value is written to its σ's
// second significant digit, not rounded to four digits whatever σ says.

#include "shell/diagnosis_report.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

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

// ρ of a fit on a flute's contact edge (a flute cuts nothing beyond it) is a lower bound, and
// the report says so in report.md and report.json; another parameter reads as before.
TEST(DiagnosisReport, ARunoutThatIsALowerBoundSaysSo) {
  diagnose::Diagnosis d;
  d.ok = true;
  d.verdict = "The model lacked runout.";
  diagnose::Stage step;
  step.added = "runout";
  step.parameters = {{"rho_um", 1.795, 0.015}, {"gamma_deg", 15.7, 0.5}};
  step.parameters[0].lower_bound = true;
  d.steps.push_back(step);
  d.named_effects = {"runout"};
  const auto dir = std::filesystem::temp_directory_path() / "millwatch_lower_bound_report";
  std::filesystem::remove_all(dir);
  write_diagnosis_report(d, dir, "lower bound", false);
  auto read = [](const std::filesystem::path& p) {
    std::ifstream in(p);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  };
  const std::string md = read(dir / "report.md");
  EXPECT_NE(md.find("rho_um ≥ 1.795 ± 0.015 (a flute cuts nothing beyond it: a lower bound), "
                    "gamma_deg = 15.7 ± 0.5"),
            std::string::npos)
      << md;
  const auto j = nlohmann::json::parse(read(dir / "report.json"));
  const auto& rho = j["steps"][0]["parameters"]["rho_um"];
  EXPECT_EQ(rho["value"], 1.795);
  EXPECT_EQ(rho["lower_bound"], true);
  EXPECT_FALSE(j["steps"][0]["parameters"]["gamma_deg"].contains("lower_bound"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace millwatch::shell
