// `millwatch replay` on recordings as users have them and with results as people read them:
// the PHM 2010 raw windows through a column map (from the command line and from a config), a
// simulated cut exported as DynoWare and as .mat v5/v7.3 giving the same results as its CSV, the
// readable summary and --json, --revolutions (CSV, JSON Lines), --plot, the progress line on a
// terminal, and a campaign of the three PHM windows replayed side by side into a table.

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <matio.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "tests/support/run_command.hpp"
#include "tests/support/test_paths.hpp"

namespace millwatch {
namespace {

namespace fs = std::filesystem;

fs::path phm_dir() {
  return test::shared_dir() / "data" / "phm2010";
}

std::string phm_config() {
  return (test::source_dir() / "config" / "phm2010_c1.json").string();
}

nlohmann::json read_json(const fs::path& p) {
  return fs::exists(p) ? nlohmann::json::parse(std::ifstream(p)) : nlohmann::json();
}

std::string read_text(const fs::path& p) {
  std::stringstream s;
  s << std::ifstream(p).rdbuf();
  return s.str();
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream s(text);
  std::string line;
  while (std::getline(s, line)) {
    out.push_back(line);
  }
  return out;
}

std::vector<std::string> split(const std::string& line, char d = ',') {
  std::vector<std::string> out;
  std::stringstream s(line);
  std::string f;
  while (std::getline(s, f, d)) {
    out.push_back(f);
  }
  if (!line.empty() && line.back() == d) {
    out.emplace_back();
  }
  return out;
}

/// `command` with its stderr discarded (run_command takes stdout and stderr together).
std::string without_log(const std::string& command) {
  std::string s = "(";
  s += command;
  s += " 2>/dev/null)";
  return s;
}

/// Runs `millwatch replay ARGS --no-identify --summary DIR/NAME.json`; the summary (null if
/// none). The formats must agree on what the monitor measures; identification (which only
/// follows from it) has its own tests.
nlohmann::json replay(const std::string& args, const fs::path& dir, const std::string& name,
                      test::CommandResult* result = nullptr) {
  const fs::path summary = dir / (name + ".json");
  const auto r = test::run_command(test::millwatch_cli() + " replay " + args +
                                   " --no-identify --summary " + summary.string() + " 2>&1");
  if (result != nullptr) {
    *result = r;
  }
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return read_json(summary);
}

/// The keys and values the formats must agree on.
void expect_same_results(const nlohmann::json& a, const nlohmann::json& b) {
  ASSERT_FALSE(a.is_null());
  ASSERT_FALSE(b.is_null());
  EXPECT_EQ(a["samples"], b["samples"]);
  EXPECT_EQ(a["revolutions"], b["revolutions"]);
  EXPECT_NEAR(a["spindle_rpm"].get<double>(), b["spindle_rpm"].get<double>(), 1e-6);
  EXPECT_NEAR(a["alpha_deg"]["mean"].get<double>(), b["alpha_deg"]["mean"].get<double>(), 1e-6);
  for (std::size_t f = 0; f < a["peak_force_N"]["resultant"].size(); ++f) {
    EXPECT_NEAR(a["peak_force_N"]["resultant"][f].get<double>(),
                b["peak_force_N"]["resultant"][f].get<double>(), 1e-9);
  }
  EXPECT_NEAR(a["delta_fy_N"].get<double>(), b["delta_fy_N"].get<double>(), 1e-9);
}

TEST(ReplayFormats, PhmRawWindowThroughAColumnMapMatchesItsCsv) {
  if (!fs::exists(phm_dir() / "c1_cut158_window_raw.csv")) {
    GTEST_SKIP() << "real recordings not found at " << phm_dir();
  }
  const fs::path dir = test::fresh_temp_dir();
  const std::string raw = (phm_dir() / "c1_cut158_window_raw.csv").string();
  const nlohmann::json csv = replay(
      (phm_dir() / "c1_cut158_window.csv").string() + " --config " + phm_config(), dir, "csv");
  // Seven columns, forces first, no time column: the rate comes from the configuration.
  test::CommandResult r;
  const nlohmann::json mapped = replay(
      raw + " --config " + phm_config() + " --columns fx=force_x_N,fy=force_y_N,fz=force_z_N", dir,
      "mapped", &r);
  expect_same_results(csv, mapped);
  EXPECT_EQ(mapped["bad_lines"], 0);
  EXPECT_NE(mapped["input_format"].get<std::string>().find("delimited text"), std::string::npos);
  // The same map as "columns" in the configuration, by index this time.
  nlohmann::json config = read_json(phm_config());
  config["columns"] = "fx=1,fy=2,fz=3";
  std::ofstream(dir / "raw_config.json") << config.dump();
  const nlohmann::json by_index =
      replay(raw + " --config " + (dir / "raw_config.json").string(), dir, "by_index");
  expect_same_results(csv, by_index);
  // A misspelt "columns" is refused with "columns" among the keys allowed (the shell reads it,
  // not the monitor's configuration, whose list had left it out).
  nlohmann::json misspelt = config;
  misspelt["colums"] = misspelt["columns"];
  misspelt.erase("columns");
  std::ofstream(dir / "misspelt.json") << misspelt.dump();
  const auto typo = test::run_command(test::millwatch_cli() + " replay " +
                                      (phm_dir() / "c1_cut158_window.csv").string() + " --config " +
                                      (dir / "misspelt.json").string() + " 2>&1");
  EXPECT_EQ(typo.exit_code, 2);
  EXPECT_NE(typo.output.find("colums: unknown key (allowed: "), std::string::npos) << typo.output;
  EXPECT_NE(typo.output.find(", columns)"), std::string::npos) << typo.output;
  // Without a rate anywhere, the error says where to put it.
  config.erase("sample_rate_hz");
  std::ofstream(dir / "no_rate.json") << config.dump();
  const auto no_rate = test::run_command(test::millwatch_cli() + " replay " + raw + " --config " +
                                         (dir / "no_rate.json").string() + " 2>&1");
  EXPECT_EQ(no_rate.exit_code, 2);
  EXPECT_NE(no_rate.output.find("c1_cut158_window_raw.csv: no time column and no sample rate: "
                                "state sample_rate_hz in --config"),
            std::string::npos)
      << no_rate.output;
  // Without a map, it says how to give one.
  const auto no_map = test::run_command(test::millwatch_cli() + " replay " + raw + " --config " +
                                        phm_config() + " 2>&1");
  EXPECT_EQ(no_map.exit_code, 2);
  EXPECT_NE(no_map.output.find("c1_cut158_window_raw.csv:1: header is \"force_x_N,force_y_N,"),
            std::string::npos)
      << no_map.output;
  EXPECT_NE(no_map.output.find("--columns t=Time,fx=Fx,fy=Fy,fz=Fz"), std::string::npos);
}

/// A simulated 0.5 s cut (CSV + sidecar); returns the CSV's path.
fs::path simulated_cut(const fs::path& dir) {
  const nlohmann::json scenario = {
      {"recording", {{"sample_rate_hz", 50000.0}, {"duration_s", 0.5}, {"seed", 3}}},
      {"spindle", {{"actual_rpm", 25252.0}}},
      {"noise", {{"enabled", true}}}};
  std::ofstream(dir / "scenario.json") << scenario.dump();
  const auto r =
      test::run_command(test::millwatch_cli() + " simulate " + (dir / "scenario.json").string() +
                        " -o " + (dir / "cut.csv").string() + " >/dev/null 2>&1");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return dir / "cut.csv";
}

struct Samples {
  std::vector<double> t, fx, fy, fz;
};

Samples read_csv(const fs::path& csv) {
  Samples s;
  const auto lines = lines_of(read_text(csv));
  for (std::size_t i = 1; i < lines.size(); ++i) {
    const auto f = split(lines[i]);
    s.t.push_back(std::stod(f[0]));
    s.fx.push_back(std::stod(f[1]));
    s.fy.push_back(std::stod(f[2]));
    s.fz.push_back(std::stod(f[3]));
  }
  return s;
}

TEST(ReplayFormats, DynoWareAndMatExportsOfACutGiveItsResults) {
  const fs::path dir = test::fresh_temp_dir();
  const fs::path csv = simulated_cut(dir);
  const Samples s = read_csv(csv);
  ASSERT_EQ(s.t.size(), 25000u);
  const std::string config = (dir / "cut.json").string();  // the sidecar describes the cut
  const nlohmann::json reference = replay(csv.string(), dir, "reference");

  // DynoWare: preamble, channels with a moment between the forces, units; time from 5 s.
  {
    std::ofstream out(dir / "export.csv");
    out << "DynoWare,Version 2.5.1.2\nFilename:,cut.dwd\nSampling rate [Hz]:,50000\n"
           "Measuring time [s]:,60\nSamples per channel:,3000001\nCycle No:,1\n"
           "Time,Fx,Fy,Mz,Fz\ns,N,N,Nm,N\n";
    char line[160];
    for (std::size_t i = 0; i < s.t.size(); ++i) {
      std::snprintf(line, sizeof line, "%.5f,%.17g,%.17g,0.5,%.17g\n", 5.0 + s.t[i], s.fx[i],
                    s.fy[i], s.fz[i]);
      out << line;
    }
  }
  test::CommandResult r;
  const nlohmann::json dyno =
      replay((dir / "export.csv").string() + " --sidecar " + config, dir, "dyno", &r);
  expect_same_results(reference, dyno);
  EXPECT_NE(dyno["input_format"].get<std::string>().find("DynoWare export"), std::string::npos);
  EXPECT_NE(dyno["input_format"].get<std::string>().find("50000 Hz stated"), std::string::npos);

  // MATLAB v5 (compressed) and v7.3: an N×3 matrix and the rate.
  for (const mat_ft version : {MAT_FT_MAT5, MAT_FT_MAT73}) {
    const fs::path mat_path = dir / (version == MAT_FT_MAT5 ? "v5.mat" : "v73.mat");
    mat_t* mat = Mat_CreateVer(mat_path.c_str(), nullptr, version);
    ASSERT_NE(mat, nullptr);
    std::vector<double> forces = s.fx;
    forces.insert(forces.end(), s.fy.begin(), s.fy.end());
    forces.insert(forces.end(), s.fz.begin(), s.fz.end());
    std::size_t dims[2] = {s.fx.size(), 3};
    matvar_t* f = Mat_VarCreate("forces", MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, forces.data(), 0);
    double rate = 50000.0;
    std::size_t one[2] = {1, 1};
    matvar_t* fs_var = Mat_VarCreate("fs", MAT_C_DOUBLE, MAT_T_DOUBLE, 2, one, &rate, 0);
    ASSERT_EQ(Mat_VarWrite(mat, f, MAT_COMPRESSION_ZLIB), 0);
    ASSERT_EQ(Mat_VarWrite(mat, fs_var, MAT_COMPRESSION_NONE), 0);
    Mat_VarFree(f);
    Mat_VarFree(fs_var);
    Mat_Close(mat);
    const nlohmann::json m =
        replay(mat_path.string() + " --sidecar " + config, dir, mat_path.stem().string());
    expect_same_results(reference, m);
    EXPECT_NE(m["input_format"].get<std::string>().find(version == MAT_FT_MAT5 ? "MATLAB v5"
                                                                               : "MATLAB v7.3"),
              std::string::npos)
        << m["input_format"];
  }

  // A damaged v7.3 file (the root group's object header claims 8 MiB) is one line of error: no
  // HDF5 diagnostics after it, nor HDF5's complaint at exit about the file it could not close.
  const fs::path damaged = dir / "damaged.mat";
  fs::copy_file(dir / "v73.mat", damaged);
  {
    std::fstream f(damaged, std::ios::in | std::ios::out | std::ios::binary);
    std::string head(12, '\0');
    f.seekg(608);
    f.read(head.data(), static_cast<std::streamsize>(head.size()));
    ASSERT_EQ(head.substr(0, 4), std::string("\x01\x00\x01\x00", 4));  // the object header
    f.seekp(618);
    f.put('\x80');
  }
  const auto bad = test::run_command(test::millwatch_cli() + " replay " + damaged.string() +
                                     " --sidecar " + config);
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find(damaged.string() +
                            ": no variable can be read from this v7.3 MAT-file (empty or "
                            "damaged: HDF5 cannot open it)\n"),
            std::string::npos)
      << bad.output;
  EXPECT_EQ(std::count(bad.output.begin(), bad.output.end(), '\n'), 1) << bad.output;
}

TEST(ReplayFormats, ReadableSummaryJsonRevolutionsAndPlots) {
  const fs::path dir = test::fresh_temp_dir();
  const fs::path csv = simulated_cut(dir);
  // The readable summary on stdout (the log on stderr).
  const auto text = test::run_command(
      without_log(test::millwatch_cli() + " replay " + csv.string() + " --revolutions " +
                  (dir / "revs.csv").string() + " --plot " + (dir / "plots").string()));
  ASSERT_EQ(text.exit_code, 0) << text.output;
  for (const char* expected :
       {"speed", "rpm measured", "25000 commanded", "revolutions", "alpha", "period [ms]",
        "peak |Fxy| [N]", "delta Fy", "residual RMS", "alerts", "warnings"}) {
    EXPECT_NE(text.output.find(expected), std::string::npos) << expected << "\n" << text.output;
  }
  EXPECT_EQ(text.output.find('{'), std::string::npos) << "no JSON without --json";
  const auto json =
      test::run_command(without_log(test::millwatch_cli() + " replay " + csv.string() +
                                    " --json --revolutions " + (dir / "revs.jsonl").string()));
  ASSERT_EQ(json.exit_code, 0);
  const nlohmann::json summary = nlohmann::json::parse(json.output);
  const int measured = summary["revolutions_measured"].get<int>();
  ASSERT_GT(measured, 150);
  // The record's in-plane force, in the JSON and on the record line.
  const double rms = summary["record_in_plane_force_N"]["rms"].get<double>();
  EXPECT_GT(rms, 0.1);
  EXPECT_GT(summary["record_in_plane_force_N"]["max"].get<double>(), rms);
  EXPECT_NE(text.output.find(fmt::format("in-plane force {:.3f} N RMS", rms)), std::string::npos)
      << text.output;
  // The identified runout, when there is one, on a line of its own.
  if (summary.contains("runout") && summary["runout"].contains("rho_um") &&
      summary["runout"]["rho_um"].is_number()) {
    EXPECT_NE(text.output.find(fmt::format("runout        {:.3f} ± ",
                                           summary["runout"]["rho_um"].get<double>())),
              std::string::npos)
        << text.output;
  } else {
    EXPECT_EQ(text.output.find("runout  "), std::string::npos) << text.output;
  }

  // One CSV row per revolution with the header's columns, α averaging to the summary's.
  const auto rows = lines_of(read_text(dir / "revs.csv"));
  ASSERT_EQ(static_cast<int>(rows.size()), measured + 1);
  const auto header = split(rows[0]);
  EXPECT_EQ(header.size(), 5u + 2u + 1u + 8u + 4u + 1u + 2u);
  EXPECT_EQ(header[0], "revolution");
  EXPECT_EQ(header[7], "alpha_deg");
  EXPECT_EQ(header[header.size() - 3], "alerts");
  EXPECT_EQ(header[header.size() - 2], "lock");
  EXPECT_EQ(header.back(), "labelling");
  double alpha_sum = 0.0;
  int valid = 0;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    const auto f = split(rows[i]);
    ASSERT_EQ(f.size(), header.size()) << rows[i];
    EXPECT_EQ(std::stoi(f[0]), static_cast<int>(i - 1));
    EXPECT_EQ(f[f.size() - 2], "1");  // one lock, no relabelling on the demo cut
    EXPECT_EQ(f.back(), "0");
    if (f[3] == "1") {
      alpha_sum += std::stod(f[7]);
      ++valid;
    }
  }
  EXPECT_EQ(valid, summary["revolutions"].get<int>());
  EXPECT_NEAR(alpha_sum / valid, summary["alpha_deg"]["mean"].get<double>(), 1e-9);
  // JSON Lines: the same revolutions, one object each.
  const auto jsonl = lines_of(read_text(dir / "revs.jsonl"));
  ASSERT_EQ(static_cast<int>(jsonl.size()), measured);
  const nlohmann::json last = nlohmann::json::parse(jsonl.back());
  EXPECT_EQ(last["revolution"], measured - 1);
  EXPECT_EQ(last["period_s"].size(), 2u);
  EXPECT_EQ(last["peak_N"]["resultant"].size(), 2u);
  EXPECT_TRUE(last["residual_rms_N"].is_object());
  EXPECT_TRUE(last["alerts"].is_array());
  EXPECT_EQ(last["lock"], 1);
  EXPECT_EQ(last["labelling"], 0);

  // Five PNGs, each a real picture of some size.
  for (const char* png :
       {"speed.png", "alpha_delta_fy.png", "flute_peaks.png", "sync_average.png", "spectrum.png"}) {
    const fs::path p = dir / "plots" / png;
    ASSERT_TRUE(fs::exists(p)) << p;
    EXPECT_GT(fs::file_size(p), 10000u) << p;
    EXPECT_EQ(read_text(p).substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8)) << p;
  }
  EXPECT_EQ(read_text(dir / "plots" / "plots.txt"), "every plot drawn\n");
  // The spectrum's data: its largest fx peak sits on a tooth-passing or spindle harmonic.
  const auto spectrum = lines_of(read_text(dir / "plots" / "spectrum.csv"));
  double best = 0.0, at_hz = 0.0;
  for (std::size_t i = 1; i < spectrum.size(); ++i) {
    const auto f = split(spectrum[i]);
    if (std::stod(f[1]) > best) {
      best = std::stod(f[1]);
      at_hz = std::stod(f[0]);
    }
  }
  const double spindle_hz = summary["spindle_rpm"].get<double>() / 60.0;
  const double k = at_hz / spindle_hz;
  EXPECT_NEAR(k, std::round(k), 0.1) << at_hz << " Hz is no harmonic of " << spindle_hz << " Hz";
}

TEST(ReplayFormats, ProgressLineOnlyOnATerminal) {
  const fs::path dir = test::fresh_temp_dir();
  const fs::path csv = simulated_cut(dir);
  // 0.5 s of recording at a quarter of real time: 2 s, then the progress line appears.
  const std::string cmd =
      test::millwatch_cli() + " replay " + csv.string() + " --speed 0.2 --no-identify";
  const auto tty = test::run_command("script -qec '" + cmd + " >/dev/null' /dev/null");
  ASSERT_EQ(tty.exit_code, 0) << tty.output;
  EXPECT_NE(tty.output.find("% "), std::string::npos) << tty.output;
  EXPECT_NE(tty.output.find("s of recording in"), std::string::npos) << tty.output;
  const auto pipe = test::run_command(cmd + " 2>&1 >/dev/null");
  ASSERT_EQ(pipe.exit_code, 0);
  EXPECT_EQ(pipe.output.find("s of recording in"), std::string::npos) << pipe.output;
}

// The optimised program (test::optimised_millwatch_cli: 42 s of a core sanitized, 11 optimised):
// the same three windows replay sanitized in tests/cli/phm2010_replay_test.cpp, and a campaign
// on as many threads as cores in ACampaignReportsAFailedCutAndExitsNonZero below.
TEST(ReplayFormats, CampaignOfThePhmWindowsShowsTheForcesRisingWithWear) {
  if (!fs::exists(phm_dir() / "c1_cut315_window.csv")) {
    GTEST_SKIP() << "real recordings not found at " << phm_dir();
  }
  const fs::path dir = test::fresh_temp_dir();
  const auto r = test::run_command(without_log(
      test::optimised_millwatch_cli() + " replay " + (phm_dir() / "c1_cut001_window.csv").string() +
      " " + (phm_dir() / "c1_cut158_window.csv").string() + " " +
      (phm_dir() / "c1_cut315_window.csv").string() + " --config " + phm_config() +
      " -j 2 --table " + (dir / "cuts.csv").string() + " --summary " +
      (dir / "summaries").string()));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto rows = lines_of(read_text(dir / "cuts.csv"));
  ASSERT_EQ(rows.size(), 4u);
  const auto header = split(rows[0]);
  auto column = [&](const std::string& name) {
    for (std::size_t i = 0; i < header.size(); ++i) {
      if (header[i] == name) {
        return i;
      }
    }
    ADD_FAILURE() << "no column " << name;
    return std::size_t{0};
  };
  std::vector<std::vector<std::string>> cut;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    cut.push_back(split(rows[i]));
    ASSERT_EQ(cut.back().size(), header.size()) << rows[i];
    EXPECT_EQ(cut.back()[column("status")], "ok");
    EXPECT_EQ(cut.back()[column("samples")], "5000");
  }
  EXPECT_NE(cut[0][column("file")].find("c1_cut001"), std::string::npos);
  EXPECT_NE(cut[2][column("file")].find("c1_cut315"), std::string::npos);
  // Cut 1: no speed, no revolutions, and the row says why.
  EXPECT_EQ(cut[0][column("spindle_rpm")], "");
  EXPECT_EQ(cut[0][column("revolutions")], "0");
  EXPECT_EQ(cut[0][column("peak_resultant_N_1")], "");
  EXPECT_NE(cut[0][column("warnings")].find("no steady tooth-passing signal"), std::string::npos);
  // Cuts 158 and 315: the same spindle, every flute's peak force rising with the wear.
  for (std::size_t c = 1; c < 3; ++c) {
    EXPECT_NEAR(std::stod(cut[c][column("spindle_rpm")]), 10400.0, 0.02 * 10400.0);
    EXPECT_GE(std::stoi(cut[c][column("revolutions")]), 15);
    EXPECT_NEAR(std::stod(cut[c][column("alpha_mean_deg")]), 120.0, 3.0);
  }
  for (const char* flute : {"peak_resultant_N_1", "peak_resultant_N_2", "peak_resultant_N_3"}) {
    EXPECT_GT(std::stod(cut[2][column(flute)]), 2.0 * std::stod(cut[1][column(flute)])) << flute;
  }
  // The whole record's in-plane force needs no revolution: it rises from cut 1 on (1.8, 17.3,
  // 52.3 N RMS; computed here from the CSVs, as √(fx² + fy²) of every row).
  for (std::size_t c = 0; c < 3; ++c) {
    const char* names[] = {"c1_cut001_window.csv", "c1_cut158_window.csv", "c1_cut315_window.csv"};
    const auto csv = lines_of(read_text(phm_dir() / names[c]));
    double sum_sq = 0.0;
    double max = 0.0;
    for (std::size_t i = 1; i < csv.size(); ++i) {
      const auto f = split(csv[i]);
      const double r2 = std::stod(f[1]) * std::stod(f[1]) + std::stod(f[2]) * std::stod(f[2]);
      sum_sq += r2;
      max = std::max(max, std::sqrt(r2));
    }
    EXPECT_NEAR(std::stod(cut[c][column("in_plane_force_rms_N")]),
                std::sqrt(sum_sq / static_cast<double>(csv.size() - 1)), 1e-5)
        << names[c];
    EXPECT_NEAR(std::stod(cut[c][column("in_plane_force_max_N")]), max, 1e-5) << names[c];
  }
  EXPECT_GT(std::stod(cut[1][column("in_plane_force_rms_N")]),
            5.0 * std::stod(cut[0][column("in_plane_force_rms_N")]));
  EXPECT_GT(std::stod(cut[2][column("in_plane_force_rms_N")]),
            2.0 * std::stod(cut[1][column("in_plane_force_rms_N")]));
  // The per-cut summaries are there too, and the table on stdout has a row per cut.
  EXPECT_EQ(read_json(dir / "summaries" / "c1_cut158_window.json")["revolutions"],
            std::stoi(cut[1][column("revolutions")]));
  // Three identification windows (0.1 s, fewer than 4) state no scatter between windows: null, not
  // 0.
  const auto spread =
      read_json(dir / "summaries" / "c1_cut315_window.json")["fit"]["window_scatter"];
  EXPECT_EQ(spread["windows"], 3) << spread.dump();
  EXPECT_TRUE(spread["rho_std_um"].is_null()) << spread.dump();
  EXPECT_TRUE(spread["rho_drift_um"].is_null()) << spread.dump();
  EXPECT_EQ(lines_of(r.output).size(), 4u) << r.output;
  EXPECT_NE(r.output.find("no steady tooth-passing signal"), std::string::npos) << r.output;
}

// A time column in milliseconds, as a semicolon export with decimal commas writes it: read as
// seconds it gives a 50 Hz rate, refused in the recording's name (the configuration's reader had
// named the configuration, whose rate was right); scaled by the column map over a units row
// ("ms"), once — not by the row's factor again (a 50 MHz rate, refused the same way).
TEST(ReplayFormats, ATimeColumnInOtherUnitsIsTheRecordingsToScale) {
  const fs::path dir = test::fresh_temp_dir();
  std::string text = "time_ms;Fx;Fy;Fz\nms;N;N;N\n";
  for (int i = 0; i < 5000; ++i) {
    const double t_ms = 0.02 * i;
    const double f = 10.0 * std::sin(2.0 * std::numbers::pi * 520.0 * t_ms * 1e-3);
    std::string row = fmt::format("{:.2f};{:.6f};{:.6f};0.0\n", t_ms, f, 0.5 * f);
    std::replace(row.begin(), row.end(), '.', ',');
    text += row;
  }
  std::ofstream(dir / "export.txt") << text;
  const std::string base = test::millwatch_cli() + " replay --no-identify " +
                           (dir / "export.txt").string() + " --config " +
                           (test::source_dir() / "config" / "phm2010_c1.json").string();
  const auto unscaled = test::run_command(base + " --columns t=time_ms,fx=Fx,fy=Fy,fz=Fz 2>&1");
  EXPECT_EQ(unscaled.exit_code, 0) << unscaled.output;  // the units row converts the ms
  const auto twice =
      test::run_command(base + " --columns t=time_ms*0.001,fx=Fx,fy=Fy,fz=Fz --summary " +
                        (dir / "s.json").string() + " 2>&1");
  ASSERT_EQ(twice.exit_code, 0) << twice.output;
  EXPECT_EQ(nlohmann::json::parse(read_text(dir / "s.json"))["sample_rate_hz"], 50000.0);
  const auto wrong = test::run_command(
      base + " --columns t=time_ms*0.000001,fx=Fx,fy=Fy,fz=Fz 2>&1");  // ns taken for ms
  EXPECT_EQ(wrong.exit_code, 2) << wrong.output;
  EXPECT_NE(wrong.output.find("export.txt: the recording's rate is 5e+07 Hz"), std::string::npos)
      << wrong.output;
  EXPECT_EQ(wrong.output.find("phm2010_c1.json: sample_rate_hz"), std::string::npos)
      << wrong.output;
}

TEST(ReplayFormats, ACampaignReportsAFailedCutAndExitsNonZero) {
  const fs::path dir = test::fresh_temp_dir();
  const fs::path csv = simulated_cut(dir);
  std::ofstream(dir / "broken.csv") << "what,is,this\n1,2,3\n";
  const auto r = test::run_command(test::millwatch_cli() + " replay --no-identify " + csv.string() +
                                   " " + (dir / "broken.csv").string() + " --sidecar " +
                                   (dir / "cut.json").string() + " --table " +
                                   (dir / "t.csv").string() + " 2>&1");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("broken.csv:1: header is \"what,is,this\""), std::string::npos)
      << r.output;
  const auto rows = lines_of(read_text(dir / "t.csv"));
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_NE(rows[1].find(",ok,"), std::string::npos) << rows[1];
  // The table says why, in the replay's own words (it had said "failed (exit 2)" alone, the
  // reason only in the log).
  EXPECT_NE(rows[2].find(",\"failed (exit 2): "), std::string::npos) << rows[2];
  EXPECT_NE(rows[2].find("broken.csv:1: header is \"\"what,is,this\"\""), std::string::npos)
      << rows[2];
}

}  // namespace
}  // namespace millwatch
