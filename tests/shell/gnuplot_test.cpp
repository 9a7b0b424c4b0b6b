// shell::run_gnuplot, gnuplot_quoted and gnuplot_text: a script that draws, one gnuplot rejects
// (its message in the log), gnuplot not found, a file name with quotes and spaces as gnuplot
// reads it, and text with a command, quotes and markup in it read literally.

#include "shell/gnuplot.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

namespace millwatch::shell {
namespace {

namespace fs = std::filesystem;

class Gnuplot : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("millwatch_gnuplot_test_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "it's here");
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path write_script(const std::string& text) const {
    const fs::path script = dir_ / "plot.gp";
    std::ofstream(script) << text;
    return script;
  }
  static std::string read(const fs::path& file) {
    std::ifstream in(file);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }

  fs::path dir_;
};

TEST_F(Gnuplot, AScriptDrawsItsPngIntoAFolderWithAQuoteInItsName) {
  const fs::path png = dir_ / "it's here" / "sine.png";
  const std::string doubled = (dir_ / "it''s here" / "sine.png").string();
  EXPECT_EQ(gnuplot_quoted(png), fmt::format("'{}'", doubled));
  const fs::path script = write_script("set terminal pngcairo size 320,240\nset output " +
                                       gnuplot_quoted(png) + "\nplot sin(x)\nunset output\n");
  EXPECT_EQ(run_gnuplot(script, dir_ / "gnuplot.log"), "");
  ASSERT_TRUE(fs::exists(png));
  std::ifstream in(png, std::ios::binary);
  std::string magic(4, '\0');
  in.read(magic.data(), 4);
  EXPECT_EQ(magic.substr(1), "PNG");
}

TEST_F(Gnuplot, AScriptGnuplotRejectsIsSaidWithItsLog) {
  const fs::path script = write_script("plot no_such_function(x)\n");
  const fs::path log = dir_ / "gnuplot.log";
  EXPECT_EQ(run_gnuplot(script, log),
            "gnuplot failed on " + script.string() + "; see " + log.string());
  EXPECT_NE(read(log).find("undefined function"), std::string::npos) << read(log);
}

TEST_F(Gnuplot, NoGnuplotOnThePathIsSaidWithWhatToInstall) {
  const char* path = std::getenv("PATH");
  const std::string before = path != nullptr ? path : "";
  ::setenv("PATH", dir_.c_str(), 1);
  const std::string problem = run_gnuplot(write_script("plot sin(x)\n"), dir_ / "gnuplot.log");
  ::setenv("PATH", before.c_str(), 1);
  EXPECT_EQ(problem,
            "cannot run gnuplot (No such file or directory); install it (Debian: gnuplot-nox)");
}

// A line break in a path would end gnuplot's string and command there, and a line after it
// starting with ! would run in the shell: such a path is refused, naming it.
TEST_F(Gnuplot, APathWithALineBreakIsRefused) {
  const fs::path evil = dir_ / "cut\n!touch ran\n.png";
  try {
    (void)gnuplot_quoted(evil);
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("cut !touch ran .png': it holds a line break"),
              std::string::npos)
        << e.what();
  }
}

TEST_F(Gnuplot, ALogThatCannotBeWrittenIsSaidAsSuch) {
  const fs::path log = dir_ / "no such folder" / "gnuplot.log";
  EXPECT_EQ(run_gnuplot(write_script("plot sin(x)\n"), log),
            "cannot write gnuplot's log " + log.string() + " (No such file or directory)");
}

// A title made of a file name reaches gnuplot as text: a backquoted command in it does not run
// (it would in a double-quoted string), quotes and markup come out as written, a line break as a
// space; for an enhanced terminal the markup gets its escape, and the title still draws.
TEST_F(Gnuplot, TextFromAFileNameIsReadLiterallyAndRunsNothing) {
  const fs::path ran = dir_ / "ran";
  const std::string name = "cut_1^2 {\"a\"} it's `touch " + ran.string() + "` @x & ~y \\n\nend";
  const fs::path printed = dir_ / "printed.txt";
  const fs::path script = write_script(
      "set print " + gnuplot_quoted(printed) + "\nprint " + gnuplot_text(name, false) + "\nprint " +
      gnuplot_text(name, true) + "\nset terminal pngcairo size 320,240 enhanced\n" + "set output " +
      gnuplot_quoted(dir_ / "titled.png") + "\nset title " + gnuplot_text(name, true) +
      "\nplot sin(x)\nunset output\n");
  EXPECT_EQ(run_gnuplot(script, dir_ / "gnuplot.log"), "") << read(dir_ / "gnuplot.log");
  EXPECT_FALSE(fs::exists(ran));
  EXPECT_TRUE(fs::exists(dir_ / "titled.png"));
  std::string plain = name;
  plain[plain.size() - 4] = ' ';  // the line break
  std::string marked;
  for (const char c : plain) {
    marked += std::string("_^{}@&~\\").find(c) != std::string::npos ? "\\" : "";
    marked += c;
  }
  EXPECT_EQ(read(printed), plain + "\n" + marked + "\n");
}

}  // namespace
}  // namespace millwatch::shell
