#include "shell/diagnosis_report.hpp"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

#include "core/diagnose/catalogue.hpp"
#include "core/diagnose/diagnosis_json.hpp"
#include "shell/gnuplot.hpp"
#include "shell/output_file.hpp"

namespace millwatch::shell {
namespace {

namespace fs = std::filesystem;
using diagnose::Diagnosis;
using diagnose::Stage;

}  // namespace

std::string value_sigma(double v, double s) {
  if (s > 0.0 && std::isfinite(s)) {
    // The value to the σ's second significant digit (at least 4 digits): 24749.998 ± 0.001, not
    // 2.475e+04 ± 0.001.
    const int digits = v != 0.0 && std::isfinite(v)
                           ? std::clamp(static_cast<int>(std::floor(std::log10(std::fabs(v))) -
                                                         std::floor(std::log10(s))) +
                                            2,
                                        4, 15)
                           : 4;
    return fmt::format("{:.{}g} ± {:.2g}", v, digits, s);
  }
  return fmt::format("{:.4g}", v);
}

namespace {

std::string stage_label(const Stage& s, std::size_t i) {
  return i == 0              ? std::string("starting model")
         : s.removed.empty() ? "+ " + s.added
                             : "+ " + s.added + " in place of " + s.removed;
}

/// The plots' data files and script; returns the PNGs it will draw.
std::vector<fs::path> write_plot_files(const Diagnosis& d, const fs::path& dir,
                                       const std::string& title, fs::path& script_path) {
  std::vector<const Stage*> stages = {&d.initial};
  for (const auto& s : d.steps) {
    stages.push_back(&s);
  }
  std::vector<fs::path> pngs;
  std::string script =
      "set terminal pngcairo size 1000,600 noenhanced\nset grid\nset datafile separator ','\n";
  for (std::size_t i = 0; i < stages.size(); ++i) {
    const Stage& s = *stages[i];
    const auto& v = s.view;
    std::string rev = "angle_deg,measured_fx_N,model_fx_N,measured_fy_N,model_fy_N\n";
    for (std::size_t g = 0; g < v.angle_deg.size(); ++g) {
      rev += fmt::format("{:.3f},{:.6g},{:.6g},{:.6g},{:.6g}\n", v.angle_deg[g], v.measured_N[0][g],
                         v.model_N[0][g], v.measured_N[1][g], v.model_N[1][g]);
    }
    const fs::path rev_csv = dir / fmt::format("revolution_{}.csv", i);
    write_text_file(rev_csv, rev);
    std::string spec = "frequency_hz,residual_fx_N,residual_fy_N\n";
    for (std::size_t b = 0; b < v.frequency_hz.size(); ++b) {
      spec += fmt::format("{:.4f},{:.6g},{:.6g}\n", v.frequency_hz[b],
                          std::max(v.residual_amplitude_N[0][b], 1e-9),
                          std::max(v.residual_amplitude_N[1][b], 1e-9));
    }
    const fs::path spec_csv = dir / fmt::format("spectrum_{}.csv", i);
    write_text_file(spec_csv, spec);
    const fs::path rev_png = dir / fmt::format("revolution_{}.png", i);
    const fs::path spec_png = dir / fmt::format("spectrum_{}.png", i);
    const std::string label = stage_label(s, i);
    script += fmt::format(
        "set output {0}\nset title {1}\n"
        "set xlabel 'model angle (deg)'\nset ylabel 'force on the tool (N)'\nset xrange [0:360]\n"
        "set key outside right\n"
        "plot {2} skip 1 using 1:2 with lines lw 2 lc rgb '#1f77b4' title 'fx measured', "
        "'' skip 1 using 1:3 with lines dt 2 lw 2 lc rgb '#0b3d66' title 'fx model', "
        "'' skip 1 using 1:4 with lines lw 2 lc rgb '#d62728' title 'fy measured', "
        "'' skip 1 using 1:5 with lines dt 2 lw 2 lc rgb '#7a1010' title 'fy model'\n"
        "set xrange [*:*]\n",
        gnuplot_quoted(rev_png),
        gnuplot_text(fmt::format("{}: {} — residual {:.4f}, {:.4f} N", title, label,
                                 s.residual_rms_N[0], s.residual_rms_N[1]),
                     false),
        gnuplot_quoted(rev_csv));
    // A white noise of RMS σ over the band has a mean bin amplitude 2σ/√(2·bins)... shown as the
    // floor's amplitude per bin: 2·σ_floor/√(n_eff).
    const double fx_level = 2.0 * d.noise_floor_N[0] / std::sqrt(std::max(1, d.effective_samples));
    const double fy_level = 2.0 * d.noise_floor_N[1] / std::sqrt(std::max(1, d.effective_samples));
    script += fmt::format(
        "set output {0}\nset title {1}\nset logscale y\nset key inside top right\n"
        "set xlabel 'frequency (Hz)'\nset ylabel 'amplitude (N)'\n"
        "plot {2} skip 1 using 1:2 with lines lc rgb '#1f77b4' title 'fx', "
        "'' skip 1 using 1:3 with lines lc rgb '#d62728' title 'fy', "
        "{3} with lines dt 2 lc rgb '#0b3d66' title 'fx noise floor (mean bin)', "
        "{4} with lines dt 2 lc rgb '#7a1010' title 'fy noise floor (mean bin)'\n"
        "unset logscale y\n",
        gnuplot_quoted(spec_png),
        gnuplot_text(fmt::format("{}: {} — residual spectrum", title, label), false),
        gnuplot_quoted(spec_csv), fx_level, fy_level);
    pngs.push_back(rev_png);
    pngs.push_back(spec_png);
  }
  script += "unset output\n";
  script_path = dir / "plots.gp";
  write_text_file(script_path, script);
  return pngs;
}

std::string parameter_text(const std::vector<diagnose::Parameter>& ps) {
  std::string out;
  for (const auto& p : ps) {
    if (!p.determined) {
      out += (out.empty() ? "" : ", ") + p.name +
             fmt::format(" = {:.4g} (not determined: the record does not pin it)", p.value);
      continue;
    }
    out += (out.empty() ? "" : ", ") + p.name +
           (p.lower_bound   ? " ≥ "
            : p.upper_bound ? " ≤ "
                            : " = ") +
           (!p.bound_note.empty() ? fmt::format("{:.4g} ({})", p.value, p.bound_note)
            : p.at_bound.empty()
                ? value_sigma(p.value, p.sigma) +
                      (p.lower_bound   ? " (a flute cuts nothing beyond it: a lower bound)"
                       : p.upper_bound ? " (a flute cuts nothing beyond it: an upper bound)"
                                       : "")
                : fmt::format("{:.4g} (at its {} physical bound: held)", p.value, p.at_bound));
  }
  return out.empty() ? "—" : out;
}

namespace {

/// A table of the candidates scored from a model, under `heading` ("" without any).
std::string candidate_table(const std::string& heading,
                            const std::vector<diagnose::CandidateScore>& cands) {
  if (cands.empty()) {
    return "";
  }
  std::string md = heading +
                   "\n\n| candidate | ΔBIC gained | residual fx / fy (N) | parameters |\n"
                   "|---|---|---|---|\n";
  for (const auto& c : cands) {
    if (c.ok) {
      md += fmt::format("| {} | {:.1f} | {:.4f} / {:.4f} | {}{} |\n", c.name, c.gain,
                        c.residual_rms_N[0], c.residual_rms_N[1], parameter_text(c.parameters),
                        c.shown ? "" : " — not chosen: " + c.message);
    } else {
      md += fmt::format("| {} | — | — | not fitted: {} |\n", c.name, c.message);
    }
  }
  return md;
}

}  // namespace

std::string markdown(const Diagnosis& d, const std::string& title, bool have_plots,
                     const std::string& plot_problem) {
  std::string md = fmt::format("# Diagnosis: {}\n\n**{}**\n\n", title, d.verdict);
  md += fmt::format(
      "Band compared: 0–{:.0f} Hz ({} independent values per axis over {:.3f} s); commanded "
      "{:.0f} rpm, model at {:.1f} rpm. Noise floor (from the data: the median of the "
      "spectrum over the band): fx {:.4f} N, fy {:.4f} N. Measured RMS over the band: fx {:.4f} N, "
      "fy {:.4f} N. Criterion: BIC with the effective number of samples; an effect must gain "
      "at least 10. Stopped: {}. Diagnosis took {:.1f} s.\n\n",
      d.band_hz, d.effective_samples, d.duration_s, d.commanded_rpm, d.spindle_rpm,
      d.noise_floor_N[0], d.noise_floor_N[1], d.measured_rms_N[0], d.measured_rms_N[1],
      d.stop_reason, d.seconds);
  md +=
      "## Steps\n\n| step | effect added | parameters (± 1σ) | residual fx (N, %) | residual fy "
      "(N, %) | × noise floor | BIC | ΔBIC gained | runner-up (ΔBIC behind) |\n"
      "|---|---|---|---|---|---|---|---|---|\n";
  std::vector<const Stage*> stages = {&d.initial};
  for (const auto& s : d.steps) {
    stages.push_back(&s);
  }
  for (std::size_t i = 0; i < stages.size(); ++i) {
    const Stage& s = *stages[i];
    const double ratio = std::max(s.residual_rms_N[0] / std::max(d.noise_floor_N[0], 1e-300),
                                  s.residual_rms_N[1] / std::max(d.noise_floor_N[1], 1e-300));
    md += fmt::format(
        "| {} | {} | {} | {:.4f} ({:.2f} %) | {:.4f} ({:.2f} %) | {:.2f} | {:.1f} | {} | {} |\n", i,
        i == 0 ? "(starting model)"
        : s.removed.empty()
            ? s.added
            : fmt::format("{} in place of {} (the exchange: ΔBIC {:.1f}{})", s.added, s.removed,
                          s.exchange_gain, s.exchange_steps == 2 ? " with the step after it" : ""),
        i == 0 ? "—"
               : (s.sigma_statistical_only && !s.parameters.empty()
                      ? parameter_text(s.parameters) + " (the window fit's σ statistical only)"
                      : parameter_text(s.parameters)) +
                     (s.newly_held.empty() ? "" : "; now held: " + parameter_text(s.newly_held)),
        s.residual_rms_N[0], s.residual_percent[0], s.residual_rms_N[1], s.residual_percent[1],
        ratio, s.criterion, i == 0 ? "—" : fmt::format("{:.1f}", s.gain),
        s.runner_up.empty() ? "—"
                            : fmt::format("{} ({:.1f})", s.runner_up, s.margin_over_runner_up));
  }
  // A step's row gives its own model's values; later steps' refits move them.
  std::string final_parameters;
  for (const auto& e : d.final_parameters) {
    if (!e.parameters.empty()) {
      final_parameters +=
          (final_parameters.empty() ? "" : "; ") + e.effect + ": " + parameter_text(e.parameters);
    }
  }
  if (!final_parameters.empty()) {
    md +=
        "\nParameters of the final model (its last fit; each step's row gives its own model's, "
        "which later steps' refits move): " +
        final_parameters + ".\n";
  }
  md += "\nForce coefficients of the final model: " + parameter_text(d.final_coefficients) + ".\n";
  for (const auto& note : d.final_notes) {
    md += "\n" + note + ".\n";
  }
  if (!d.sigma_caveat.empty()) {
    md += "\n" + d.sigma_caveat + "\n";
  }
  if (!d.at_bound.empty()) {
    md += fmt::format(
        "\nOn a physical bound (a clamped piezoelectric dynamometer's range: damping ratio "
        "{:g}–{:g}, natural frequency {:g}–{:g} Hz; the fit wanted a value outside, the rest was "
        "refitted with it held): {}.\n",
        diagnose::kDampingRatioMin, diagnose::kDampingRatioMax, diagnose::kNaturalHzMin,
        diagnose::kNaturalHzMax, parameter_text(d.at_bound));
  }
  for (std::size_t i = 0; i < stages.size(); ++i) {
    const Stage& s = *stages[i];
    const Stage& scored = i + 1 < stages.size() ? *stages[i + 1] : s;
    md += fmt::format("\n## Stage {}: {}\n\nWhere the residual is: {}.\n\n", i, stage_label(s, i),
                      s.localisation.summary);
    md +=
        "| frequency band | holds | residual fx / fy (N) | noise's share fx / fy (N) |\n"
        "|---|---|---|---|\n";
    for (const auto& b : s.localisation.bands) {
      md += fmt::format("| {} | {} | {:.4f} / {:.4f} | {:.4f} / {:.4f} |\n", b.name, b.range,
                        b.rms_N[0], b.rms_N[1], b.noise_rms_N[0], b.noise_rms_N[1]);
    }
    md += "\nSynchronous residual per flute (fx / fy, N): ";
    for (std::size_t j = 0; j < s.localisation.flute_rms_N.size(); ++j) {
      md += fmt::format("{}CE{} {:.4f} / {:.4f}", j == 0 ? "" : "; ", j + 1,
                        s.localisation.flute_rms_N[j][0], s.localisation.flute_rms_N[j][1]);
    }
    md += fmt::format(
        ". By angle: entry/exit {:.4f} / {:.4f} N, middle {:.4f} / {:.4f} N. By time (band-limited "
        "residual per eighth of the record, |F| N): ",
        s.localisation.entry_exit_rms_N[0], s.localisation.entry_exit_rms_N[1],
        s.localisation.middle_rms_N[0], s.localisation.middle_rms_N[1]);
    for (std::size_t k = 0; k < s.localisation.segment_rms_N.size(); ++k) {
      md += fmt::format(
          "{}{:.4f}", k == 0 ? "" : ", ",
          std::hypot(s.localisation.segment_rms_N[k][0], s.localisation.segment_rms_N[k][1]));
    }
    md += ".\n";
    // From this model: the round that chose the next stage, or after the last, the final round.
    // Before an exchange, the round in which nothing gained, then the exchange's round, scored
    // from the model without the effect it replaces.
    const bool exchange_next = i + 1 < stages.size() && !scored.removed.empty();
    if (exchange_next) {
      md += candidate_table("\nCandidates scored from this model (none gained enough):",
                            scored.candidates_before_exchange);
      md += candidate_table("\nCandidates scored from this model without " + scored.removed +
                                " (the exchange's round; ΔBIC against the model without it):",
                            scored.candidates);
    } else {
      md += candidate_table("\nCandidates scored from this model:",
                            i + 1 < stages.size() ? scored.candidates : d.final_candidates);
    }
    if (have_plots) {
      md += fmt::format(
          "\n![stage {0} revolution](revolution_{0}.png)\n"
          "![stage {0} spectrum](spectrum_{0}.png)\n",
          i);
    }
  }
  if (!have_plots) {
    md += "\nPlots: not drawn (" + plot_problem + "); their data are in the CSV files.\n";
  }
  md +=
      "\n## Catalogue\n\n| candidate | signature | extension | free parameters |\n"
      "|---|---|---|---|\n";
  for (const auto& c : diagnose::catalogue()) {
    md += fmt::format("| {} | {} | {} | {} |\n", c.name, c.signature, c.extension, c.parameters);
  }
  return md;
}

std::string html_escape(const std::string& s) {
  std::string out;
  for (const char c : s) {
    switch (c) {
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '&':
        out += "&amp;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

/// The markdown as HTML: headings, paragraphs, tables and images (the subset written above).
std::string html(const std::string& md, const std::string& title) {
  std::string out = "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>" +
                    html_escape(title) +
                    "</title><style>body{font-family:sans-serif;max-width:1200px;margin:auto}"
                    "table{border-collapse:collapse}td,th{border:1px solid #999;padding:2px 6px}"
                    "img{max-width:48%}</style></head><body>\n";
  std::size_t pos = 0;
  bool in_table = false;
  while (pos < md.size()) {
    std::size_t end = md.find('\n', pos);
    if (end == std::string::npos) {
      end = md.size();
    }
    const std::string line = md.substr(pos, end - pos);
    pos = end + 1;
    const bool row = !line.empty() && line[0] == '|';
    if (in_table && !row) {
      out += "</table>\n";
      in_table = false;
    }
    if (row) {
      if (line.rfind("|---", 0) == 0) {
        continue;
      }
      out += in_table ? "<tr>" : "<table><tr>";
      const bool head = !in_table;
      in_table = true;
      std::size_t c = 1;
      while (c < line.size()) {
        const std::size_t e = line.find('|', c);
        if (e == std::string::npos) {
          break;
        }
        out += (head ? "<th>" : "<td>") + html_escape(line.substr(c + 1, e - c - 2)) +
               (head ? "</th>" : "</td>");
        c = e + 1;
      }
      out += "</tr>\n";
    } else if (line.rfind("## ", 0) == 0) {
      out += "<h2>" + html_escape(line.substr(3)) + "</h2>\n";
    } else if (line.rfind("# ", 0) == 0) {
      out += "<h1>" + html_escape(line.substr(2)) + "</h1>\n";
    } else if (line.rfind("![", 0) == 0) {
      const std::size_t a = line.find("](");
      out += "<img src=\"" + html_escape(line.substr(a + 2, line.size() - a - 3)) + "\" alt=\"" +
             html_escape(line.substr(2, a - 2)) + "\">\n";
    } else if (!line.empty()) {
      std::string text = html_escape(line);
      if (text.rfind("**", 0) == 0 && text.size() > 4) {
        text = "<b>" + text.substr(2, text.size() - 4) + "</b>";
      }
      out += "<p>" + text + "</p>\n";
    }
  }
  if (in_table) {
    out += "</table>\n";
  }
  return out + "</body></html>\n";
}

/// Creates the report folder (and its parents) and returns its absolute path.
fs::path report_folder(const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) {
    throw std::runtime_error(dir.string() + ": cannot create the report folder (" + ec.message() +
                             ")");
  }
  return fs::absolute(dir);
}

/// Writes one of the report's files and lists it.
void write_report_file(const fs::path& path, const std::string& text, ReportFiles& out) {
  write_text_file(path, text);
  out.written.push_back(path);
}

}  // namespace

ReportFiles write_diagnosis_report(const Diagnosis& d, const fs::path& dir,
                                   const std::string& title, bool plots) {
  ReportFiles out;
  const fs::path abs = report_folder(dir);
  write_report_file(abs / "report.json", diagnose::to_json(d).dump(2) + "\n", out);
  bool have_plots = false;
  if (plots) {
    fs::path script;
    const auto pngs = write_plot_files(d, abs, title, script);
    out.plot_problem = run_gnuplot(script, abs / "gnuplot.log");
    have_plots = out.plot_problem.empty();
    if (have_plots) {
      out.written.insert(out.written.end(), pngs.begin(), pngs.end());
    }
  } else {
    out.plot_problem = "--no-plots";
  }
  const std::string md = markdown(d, title, have_plots, out.plot_problem);
  write_report_file(abs / "report.md", md, out);
  write_report_file(abs / "report.html", html(md, "Diagnosis: " + title), out);
  return out;
}

namespace {

std::string trend_text(const diagnose::FeedTrend& t) {
  if (!t.has_exponent) {
    return t.name + " (" + t.sentence + ")";
  }
  return fmt::format("{} (exponent {:.2f}{}, mostly in {})", t.name, t.exponent,
                     t.has_sigma ? fmt::format(" ± {:.2f}", t.exponent_sigma) : std::string(),
                     t.band);
}

std::string across_markdown(const diagnose::AcrossFeeds& a, const std::vector<CutReport>& cuts,
                            bool have_plot, const std::string& plot_problem) {
  std::string md =
      fmt::format("# Diagnosis across feeds ({} cuts)\n\n**{}**\n\n", a.cuts.size(), a.verdict);
  md += "Starting model's residual against the feed: " + a.trend.sentence + "\n\n";
  md += "After each cut's diagnosis: " + trend_text(a.trend_after) + ".\n\n";
  md +=
      "| cut | f_t (µm) | measured fx / fy (N) | noise floor fx / fy (N) | residual before fx / fy "
      "(N) | spindle harm. / tooth harm. / rest, fx (N) | excess before (N) | residual after fx / "
      "fy (N) | excess after (N) | effects named |\n|---|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& c : a.cuts) {
    std::string named;
    for (const auto& e : c.named_effects) {
      named += (named.empty() ? "" : ", ") + e;
    }
    md += fmt::format(
        "| {} | {:.3g} | {:.4f} / {:.4f} | {:.4f} / {:.4f} | {:.4f} / {:.4f} | {:.4f} / {:.4f} / "
        "{:.4f} | {:.4f} | {:.4f} / {:.4f} | {:.4f} | {} |\n",
        c.name, c.feed_per_tooth_um, c.measured_rms_N[0], c.measured_rms_N[1], c.noise_floor_N[0],
        c.noise_floor_N[1], c.before.total_N[0], c.before.total_N[1],
        c.before.spindle_harmonics_N[0], c.before.tooth_harmonics_N[0], c.before.rest_N[0],
        c.before.excess_N, c.after.total_N[0], c.after.total_N[1], c.after.excess_N,
        named.empty() ? "—" : named);
  }
  md +=
      "\nExcess: the residual above the noise floor, √(Σ max(r² − floor², 0)) over fx and fy. "
      "The trend reads excess ∝ f_t^n: n ≥ 0.6 proportional to the feed (a coefficient or law "
      "error), −0.4 < n < 0.6 independent of it (runout's fixed chip error, the measurement "
      "chain), n ≤ −0.4 growing as the feed falls (ploughing below h_min, accumulation).\n\n";
  md += "Each cut's own report:\n\n";
  for (const auto& c : cuts) {
    md += fmt::format("- {}: {}/report.md — {}\n", c.name, c.folder,
                      c.diagnosis != nullptr ? c.diagnosis->verdict : "");
  }
  if (have_plot) {
    md += "\n![residual vs feed](residual_vs_feed.png)\n";
  } else {
    md += "\nPlot: not drawn (" + plot_problem + "); its data are in residual_vs_feed.csv.\n";
  }
  return md;
}

}  // namespace

ReportFiles write_across_feeds_report(const diagnose::AcrossFeeds& across,
                                      const std::vector<CutReport>& cuts, const fs::path& dir,
                                      bool plots) {
  ReportFiles out;
  const fs::path abs = report_folder(dir);
  nlohmann::json list = nlohmann::json::array();
  for (const auto& c : cuts) {
    nlohmann::json j = {{"cut", c.name}, {"report", c.folder + "/report.json"}};
    for (const auto& a : across.cuts) {
      if (a.name == c.name) {
        j["feed_per_tooth_um"] = a.feed_per_tooth_um;
      }
    }
    if (c.diagnosis != nullptr) {
      const nlohmann::json d = diagnose::to_json(*c.diagnosis);
      for (const char* key : {"named_effects", "verdict", "initial_residual_rms_N",
                              "final_residual_rms_N", "noise_floor_N"}) {
        j[key] = d[key];
      }
    }
    list.push_back(j);
  }
  const nlohmann::json report = {{"cuts", list},
                                 {"across_feeds", diagnose::to_json(across)},
                                 {"named_effects", across.named_in_every_cut},
                                 {"verdict", across.verdict}};
  write_report_file(abs / "report.json", report.dump(2) + "\n", out);
  std::string csv =
      "feed_per_tooth_um,residual_before_N,residual_after_N,excess_before_N,excess_after_N,"
      "noise_floor_N\n";
  for (const auto& c : across.cuts) {
    csv += fmt::format("{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g}\n", c.feed_per_tooth_um,
                       std::hypot(c.before.total_N[0], c.before.total_N[1]),
                       std::hypot(c.after.total_N[0], c.after.total_N[1]),
                       std::max(c.before.excess_N, 1e-6), std::max(c.after.excess_N, 1e-6),
                       std::hypot(c.noise_floor_N[0], c.noise_floor_N[1]));
  }
  const fs::path csv_path = abs / "residual_vs_feed.csv";
  write_text_file(csv_path, csv);
  bool have_plot = false;
  if (plots) {
    const fs::path png = abs / "residual_vs_feed.png";
    const std::string script = fmt::format(
        "set terminal pngcairo size 900,600 noenhanced\nset grid\nset datafile separator ','\n"
        "set output {0}\nset title {1}\nset logscale xy\n"
        "set xlabel 'feed per tooth (um)'\nset ylabel '|residual| over fx, fy (N)'\n"
        "set key outside right\n"
        "plot {2} skip 1 using 1:2 with linespoints lw 2 pt 7 lc rgb '#d62728' title 'starting "
        "model', '' skip 1 using 1:3 with linespoints lw 2 pt 7 lc rgb '#1f77b4' title 'after the "
        "diagnosis', '' skip 1 using 1:4 with linespoints dt 3 pt 6 lc rgb '#d62728' title "
        "'excess before', '' skip 1 using 1:6 with lines dt 2 lc rgb '#555555' title 'noise "
        "floor'\nunset output\n",
        gnuplot_quoted(png), gnuplot_text("residual against the feed: " + across.trend.name, false),
        gnuplot_quoted(csv_path));
    const fs::path script_path = abs / "residual_vs_feed.gp";
    write_text_file(script_path, script);
    out.plot_problem = run_gnuplot(script_path, abs / "gnuplot.log");
    have_plot = out.plot_problem.empty();
    if (have_plot) {
      out.written.push_back(png);
    }
  } else {
    out.plot_problem = "--no-plots";
  }
  const std::string md = across_markdown(across, cuts, have_plot, out.plot_problem);
  write_report_file(abs / "report.md", md, out);
  write_report_file(abs / "report.html", html(md, "Diagnosis across feeds"), out);
  return out;
}

}  // namespace millwatch::shell
