#include "shell/run_plots.hpp"

#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <stdexcept>

#include "core/signal/welch_spectrum.hpp"
#include "shell/gnuplot.hpp"

namespace millwatch::shell {
namespace {

namespace fs = std::filesystem;

void write_file(const fs::path& p, const std::string& text) {
  std::ofstream out(p, std::ios::binary);
  out << text;
  if (!out) {
    throw std::runtime_error(p.string() + ": cannot write");
  }
}

std::string num(double v) {
  return std::isfinite(v) ? fmt::format("{:.9g}", v) : std::string("NaN");
}

const char* kTerminal =
    "set terminal pngcairo size 1200,700 font 'DejaVu Sans,12' linewidth 1.5\n"
    "set datafile separator ','\n"
    "set grid lc rgb '#d0d0d0'\n"
    "set key inside right top opaque box samplen 2 spacing 1.1\n"
    "set lmargin 12\n"
    "set rmargin 4\n"
    "set border lw 1\n";

const char* kFluteColours[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd",
                               "#ff7f0e", "#8c564b", "#e377c2", "#17becf"};

}  // namespace

std::vector<fs::path> write_plots(const RunRecorder& rec, const nlohmann::json& summary,
                                  const fs::path& dir, const std::string& title) {
  fs::create_directories(dir);
  const fs::path abs = fs::absolute(dir);
  const int flutes = rec.flutes();
  std::string script = kTerminal;
  std::string notes;
  std::vector<fs::path> pngs;
  // Each title gnuplot reads literally (a file name's markup and backquotes too).
  const auto titled = [&](const std::string& what) {
    return gnuplot_text(title + " — " + what, true);
  };
  const double commanded = summary.value("spindle_rpm_commanded", 0.0);
  const double rpm = summary.contains("spindle_rpm") && summary["spindle_rpm"].is_number()
                         ? summary["spindle_rpm"].get<double>()
                         : 0.0;
  auto add_png = [&](const std::string& name) {
    pngs.push_back(abs / name);
    script += "set output " + gnuplot_quoted(abs / name) + "\n";
  };

  // Revolutions with their bounds as data (α and ΔFy NaN, a gap, where not every event was
  // found: the summary's rule).
  std::string rows = "revolution,t_s,spindle_rpm,alpha_deg,delta_fy_N";
  for (int j = 1; j <= flutes; ++j) {
    rows += fmt::format(",peak_resultant_N_{}", j);
  }
  rows += "\n";
  std::size_t valid = 0;
  std::size_t bounded = 0;
  const double nan = std::nan("");
  for (const auto& r : rec.rows()) {
    if (!r.bounded) {
      continue;
    }
    ++bounded;
    valid += r.valid ? 1 : 0;
    rows += fmt::format("{},{},{},{},{}", r.revolution, num(r.t_s), num(r.spindle_rpm),
                        num(r.valid ? r.alpha_deg : nan), num(r.valid ? r.delta_fy_N : nan));
    for (int j = 0; j < flutes; ++j) {
      rows += ',';
      rows += num(r.peak_resultant_N[static_cast<std::size_t>(j)]);
    }
    rows += "\n";
  }
  write_file(abs / "revolutions.csv", rows);
  std::string speed = "t_s,spindle_rpm\n";
  for (const auto& p : rec.spindle()) {
    speed += num(p.t_s) + "," + num(p.rpm) + "\n";
  }
  write_file(abs / "spindle.csv", speed);
  const fs::path rev_csv = abs / "revolutions.csv";

  // 1. Speed over time.
  if (!rec.spindle().empty() || bounded > 0) {
    add_png("speed.png");
    script += fmt::format("set title {}\nset xlabel 'time [s]'\nset ylabel 'speed [rpm]'\n",
                          titled(fmt::format("spindle speed (commanded {:.0f} rpm)", commanded)));
    std::string plot = "plot ";
    if (!rec.spindle().empty()) {
      plot += gnuplot_quoted(abs / "spindle.csv") +
              " skip 1 using 1:2 with points pt 7 ps 0.6 lc rgb '#7f7f7f' title 'tracker "
              "(spectrum windows)'";
    }
    if (bounded > 0) {
      plot += std::string(plot.size() > 5 ? ", " : "") + gnuplot_quoted(rev_csv) +
              " skip 1 using 2:3 with lines lc rgb '#1f77b4' lw 2 title 'each revolution'";
    }
    script += plot + "\n";
  } else {
    notes += "speed.png: left out, no speed was measured\n";
  }

  // 2. α and ΔFy per revolution; 3. per-flute peaks.
  if (valid > 0 && flutes > 1) {
    add_png("alpha_delta_fy.png");
    script += fmt::format(
        "set multiplot layout 2,1 title {}\nunset title\n"
        "set xlabel ''\nset ylabel 'alpha [deg]'\n"
        "plot {} skip 1 using 1:4 with linespoints pt 7 ps 0.4 lc rgb '#1f77b4' title 'alpha'\n"
        "set xlabel 'revolution'\nset ylabel 'delta Fy [N]'\n"
        "plot {} skip 1 using 1:5 with linespoints pt 7 ps 0.4 lc rgb '#d62728' title 'delta "
        "Fy = |Fy peak CE1| - |Fy peak CE2|'\n"
        "unset multiplot\n",
        titled("per revolution"), gnuplot_quoted(rev_csv), gnuplot_quoted(rev_csv));
  } else if (flutes < 2) {
    notes += "alpha_delta_fy.png: left out, one flute (α and ΔFy compare two cutting edges)\n";
  } else {
    notes += "alpha_delta_fy.png: left out, no revolution had all its tooth events found\n";
  }
  if (bounded > 0) {
    add_png("flute_peaks.png");
    script +=
        fmt::format("set title {}\nset xlabel 'revolution'\nset ylabel 'peak |Fxy| [N]'\nplot ",
                    titled("peak in-plane force per flute"));
    for (int j = 0; j < flutes; ++j) {
      script += fmt::format(
          "{}{} skip 1 using 1:{} with linespoints pt 7 ps 0.4 lc rgb '{}' title 'flute {}{}'",
          j > 0 ? ", " : "", gnuplot_quoted(rev_csv), 6 + j, kFluteColours[j % 8], j + 1,
          j == 0 ? " (CE1)" : "");
    }
    script += "\n";
  } else {
    notes += "flute_peaks.png: left out, no revolution was measured\n";
  }

  // 4. Synchronous average, measured vs model.
  const auto& sync = rec.sync();
  if (!sync.measured[0].empty()) {
    const std::size_t bins = sync.measured[0].size();
    std::string data = "angle_deg,fx_N,fy_N,fz_N,model_fx_N,model_fy_N,model_fz_N\n";
    for (std::size_t b = 0; b <= bins; ++b) {  // closed: the first bin again at 360°
      const std::size_t i = b % bins;
      data += num(360.0 * static_cast<double>(b) / static_cast<double>(bins));
      for (std::size_t a = 0; a < 3; ++a) {
        data += ',';
        data += num(sync.measured[a][i]);
      }
      for (std::size_t a = 0; a < 3; ++a) {
        data += ',';
        data += num(sync.model[a][i]);
      }
      data += "\n";
    }
    write_file(abs / "sync_average.csv", data);
    add_png("sync_average.png");
    script += fmt::format(
        "set multiplot layout 3,1 title {}\nunset title\nset xrange [0:360]\nset xtics 45\n",
        titled(fmt::format("synchronous average of {} revolutions (at revolution {}), force on "
                           "the tool",
                           sync.window_revolutions, sync.revolution)));
    const char* axes[] = {"Fx", "Fy", "Fz"};
    for (int a = 0; a < 3; ++a) {
      script += fmt::format(
          "set ylabel '{} [N]'\nset xlabel '{}'\nplot {} skip 1 using 1:{} with "
          "lines lw 2 lc rgb '#1f77b4' title 'measured'",
          axes[a], a == 2 ? "spindle angle [deg]" : "", gnuplot_quoted(abs / "sync_average.csv"),
          2 + a);
      if (sync.model_valid) {
        script += fmt::format(
            ", '' skip 1 using 1:{} with lines lw 2 dt 2 lc rgb '#d62728' "
            "title 'model'",
            5 + a);
      }
      script += "\n";
    }
    script += "unset multiplot\nset xrange [*:*]\nset xtics autofreq\n";
    if (!sync.model_valid) {
      notes += "sync_average.png: the model was not aligned; measured only\n";
    }
  } else {
    notes += "sync_average.png: left out, no synchronous average (no lock)\n";
  }

  // 5. Spectrum with the tooth-passing harmonics.
  if (rec.raw()[0].size() >= 256 && rec.raw_rate_hz() > 0.0) {
    const auto sx = signal::welch_amplitude_spectrum(rec.raw()[0], rec.raw_rate_hz(), 1 << 15);
    const auto sy = signal::welch_amplitude_spectrum(rec.raw()[1], rec.raw_rate_hz(), 1 << 15);
    const auto sz = signal::welch_amplitude_spectrum(rec.raw()[2], rec.raw_rate_hz(), 1 << 15);
    const std::vector<double>& f = sx.frequency_hz;
    const std::vector<double>&ax = sx.amplitude, &ay = sy.amplitude, &az = sz.amplitude;
    const double spindle_hz = (rpm > 0.0 ? rpm : commanded) / 60.0;
    const double tooth_hz = spindle_hz * flutes;
    const double f_max = std::min(rec.raw_rate_hz() / 2.0,
                                  tooth_hz > 0.0 ? 10.5 * tooth_hz : rec.raw_rate_hz() / 2.0);
    std::string data = "frequency_hz,fx_N,fy_N,fz_N\n";
    for (std::size_t k = 1; k < f.size() && f[k] <= f_max; ++k) {
      data += num(f[k]) + "," + num(ax[k]) + "," + num(ay[k]) + "," + num(az[k]) + "\n";
    }
    write_file(abs / "spectrum.csv", data);
    add_png("spectrum.png");
    const std::size_t total = rec.raw()[0].size();
    const std::size_t segments = sx.segments, segment = sx.segment, covered = sx.covered;
    script += fmt::format(
        "set title {}\nset xlabel 'frequency [Hz]'\nset ylabel 'amplitude [N]'\nset logscale y\n"
        "set format y '10^{{%L}}'\nset xrange [0:{}]\nset key bottom right\n",
        titled(fmt::format("force spectrum ({} of the {} samples as recorded, in {} Hann "
                           "segment(s) of {}; {:.1f} Hz resolution)",
                           covered, total, segments, segment, f.size() > 1 ? f[1] : 0.0)),
        num(f_max));
    if (tooth_hz > 0.0) {
      for (int k = 1; k * tooth_hz <= f_max; ++k) {
        script += fmt::format(
            "set arrow from {0},graph 0 to {0},graph 1 nohead dt 3 lw 1 lc rgb '#555555'\n"
            "set label '{1}×' at {0},graph 0.97 offset 0.3,0 font ',9' tc rgb '#555555'\n",
            num(k * tooth_hz), k);
      }
    }
    script += fmt::format(
        "plot {0} skip 1 using 1:2 with lines lc rgb '#1f77b4' title 'fx', '' skip 1 using "
        "1:3 with lines lc rgb '#d62728' title 'fy', '' skip 1 using 1:4 with lines lc rgb "
        "'#2ca02c' title 'fz', NaN with lines dt 3 lc rgb '#555555' title 'k × tooth passing "
        "({1:.1f} Hz{2})'\n"
        "unset logscale y\nunset arrow\nunset label\nset xrange [*:*]\nunset format\n"
        "set key top right\n",
        gnuplot_quoted(abs / "spectrum.csv"), tooth_hz, rpm > 0.0 ? ", measured" : ", commanded");
  } else {
    notes += "spectrum.png: left out, too few samples\n";
  }
  script += "unset output\n";
  write_file(abs / "plots.gp", script);
  write_file(abs / "plots.txt", notes.empty() ? "every plot drawn\n" : notes);

  // gnuplot plots.gp, its messages in gnuplot.log.
  if (const std::string problem = run_gnuplot(abs / "plots.gp", abs / "gnuplot.log");
      !problem.empty()) {
    throw std::runtime_error("--plot: " + problem);
  }
  return pngs;
}

}  // namespace millwatch::shell
