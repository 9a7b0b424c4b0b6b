// The command line as a new user meets it, across the commands: numbers outside what they mean,
// a word that is no command, --version, options that exclude each other, the daemon's URLs.

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <utility>

#include "tests/support/run_command.hpp"
#include "tests/support/test_paths.hpp"

namespace millwatch {
namespace {

namespace fs = std::filesystem;

// Numbers outside what they mean are refused before anything runs (as simulate's are): publish
// --start-utime nan had published every block at utime −2⁶³ (an unchecked cast), diagnose --band −5
// or nan had been taken for the default band without a word.
TEST(CommandLine, NumbersOutsideWhatTheyMeanAreRefusedBeforeAnythingRuns) {
  const std::string scenario = (test::source_dir() / "config" / "demo.json").string();
  const fs::path log = test::fresh_temp_dir() / "never.lcmlog";
  const std::string publish = test::millwatch_cli() + " publish " + scenario +
                              " --duration 0.01 --speed 0 --url 'file://" + log.string() +
                              "?mode=w' ";
  const std::string diagnose = test::millwatch_cli() + " diagnose " + scenario + " --report " +
                               (log.parent_path() / "report").string() + " ";
  const std::pair<std::string, const char*> cases[] = {
      {publish + "--start-utime nan", "--start-utime: \"nan\" is not a number"},
      {publish + "--start-utime -1", "--start-utime: -1 is not a non-negative number"},
      {publish + "--start-utime 9e9", "--start-utime: 9e9 is beyond 4e+09"},
      {diagnose + "--band -5", "--band: -5 is not a positive number"},
      {diagnose + "--band nan", "--band: \"nan\" is not a number"},
      {diagnose + "--from-s -1", "--from-s: -1 is not a non-negative number"},
      {diagnose + "--from-s 0.07 --to-s 0.02", "--to-s 0.02 is not after --from-s 0.07"},
      // Whole numbers: CLI11's range check had called "abc" and 2.5 "not in range 0 to 256".
      {diagnose + "-j abc", "--jobs: \"abc\" is not a whole number"},
      {diagnose + "-j 2.5", "--jobs: \"2.5\" is not a whole number"},
      {diagnose + "-j 300", "--jobs: 300 is not in [0, 256]"},
      {test::millwatch_cli() + " replay " + scenario + " --block 0",
       "--block: 0 is not in [1, 65536]"},
      {test::millwatch_cli() + " simulate " + scenario + " --seed -3",
       "--seed: -3 is not a non-negative whole number"},
      // A feed the model does not take: the model's reader had blamed the configuration.
      {test::millwatch_cli() + " calibrate " + scenario + " --feeds-um 1e9",
       "--feeds-um: 1e9 is beyond 1000"},
      {diagnose + "--feeds-um abc", "--feeds-um: \"abc\" is not a number"},
      // Outputs that cannot be written, said before the work (calibrate's fit: seconds to
      // minutes; it had failed after it, naming no option).
      {test::millwatch_cli() + " calibrate " + scenario + " -o /proc/no_such_folder/m.json",
       "-o /proc/no_such_folder/m.json: no folder /proc/no_such_folder"},
      {test::millwatch_cli() + " replay " + scenario + " --plot /proc/no_such_folder",
       "--plot /proc/no_such_folder: cannot make the folder"},
      {test::millwatch_cli() + " replay " + scenario + " --summary /proc/no_such_folder/s.json",
       "--summary /proc/no_such_folder/s.json: no folder /proc/no_such_folder"}};
  for (const auto& [command, said] : cases) {
    const auto r = test::run_command(command + " 2>&1");
    EXPECT_NE(r.exit_code, 0) << command;
    EXPECT_NE(r.output.find(said), std::string::npos) << r.output;
  }
  EXPECT_FALSE(fs::exists(log));
  EXPECT_FALSE(fs::exists(log.parent_path() / "report"));
}

// The command line as a new user tries it: a word that is no command is named as such (it had
// said "A subcommand is required"), --version answers, --speed and --realtime are not both taken
// (--realtime had won silently), the daemon's --lcm-url is checked like its file's.
TEST(CommandLine, SaysWhatItDoesNotKnow) {
  const std::string cli = test::millwatch_cli();
  const auto bogus = test::run_command(cli + " simulat 2>&1");
  EXPECT_NE(bogus.exit_code, 0);
  EXPECT_NE(bogus.output.find("millwatch: no command \"simulat\" (commands: simulate, replay, "
                              "publish, record, calibrate, diagnose"),
            std::string::npos)
      << bogus.output;
  const auto version = test::run_command(cli + " --version 2>&1");
  EXPECT_EQ(version.exit_code, 0);
  EXPECT_EQ(version.output.rfind("millwatch 0.", 0), 0u) << version.output;
  const std::string demo = (test::source_dir() / "config" / "demo.json").string();
  const auto both = test::run_command(cli + " replay " + demo + " --speed 4 --realtime 2>&1");
  EXPECT_NE(both.exit_code, 0);
  EXPECT_NE(both.output.find("excludes"), std::string::npos) << both.output;
  const auto url = test::run_command(std::string(MILLWATCH_DAEMON) + " -c " +
                                     (test::source_dir() / "config" / "millwatchd.json").string() +
                                     " --check --lcm-url udp://239.255.76.67:7667 2>&1");
  EXPECT_NE(url.exit_code, 0);
  EXPECT_NE(url.output.find("--lcm-url: \"udp://239.255.76.67:7667\": no LCM provider \"udp\""),
            std::string::npos)
      << url.output;
}

}  // namespace
}  // namespace millwatch
