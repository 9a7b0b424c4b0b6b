#include "shell/cut_table.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace millwatch::shell {
namespace {

using nlohmann::json;

/// A number at a JSON pointer, or NaN.
double at(const json& j, const char* pointer) {
  const json::json_pointer p(pointer);
  return j.is_object() && j.contains(p) && j[p].is_number() ? j[p].get<double>() : std::nan("");
}

std::string csv_number(double v, const char* format = "{:.9g}") {
  return std::isfinite(v) ? fmt::format(fmt::runtime(format), v) : std::string();
}

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) {
    return s;
  }
  std::string q = "\"";
  for (char c : s) {
    q += c == '"' ? std::string("\"\"") : std::string(1, c);
  }
  return q + "\"";
}

int flutes_of(const std::vector<CutResult>& cuts) {
  std::size_t flutes = 0;
  for (const auto& c : cuts) {
    if (c.summary.is_object() && c.summary.contains("peak_force_N")) {
      flutes = std::max(flutes, c.summary["peak_force_N"].value("resultant", json::array()).size());
    }
  }
  return static_cast<int>(flutes);
}

std::string status(const CutResult& c) {
  if (c.exit_code == 0 && c.summary.is_object()) {
    return "ok";
  }
  if (c.summary.is_object()) {  // stopped by a signal: its summary covers what it replayed
    return fmt::format("interrupted (exit {}): partial", c.exit_code);
  }
  return fmt::format("failed (exit {}){}{}", c.exit_code, c.error.empty() ? "" : ": ", c.error);
}

/// The warnings' kinds, "; "-separated.
std::string warning_kinds(const json& s) {
  std::string out;
  for (const auto& w : s.value("warnings", json::array())) {
    if (!out.empty()) {
      out += "; ";
    }
    out += w.value("kind", std::string("?"));
  }
  return out;
}

std::int64_t alerts_raised(const json& s) {
  std::int64_t n = 0;
  for (const auto& a : s.value("alerts", json::array())) {
    n += a.value("active", false) ? 1 : 0;
  }
  return n;
}

double peak(const json& s, int flute) {
  if (!s.is_object() || !s.contains("peak_force_N")) {
    return std::nan("");
  }
  const json& r = s["peak_force_N"].value("resultant", json::array());
  const auto f = static_cast<std::size_t>(flute);
  return f < r.size() && r[f].is_number() ? r[f].get<double>() : std::nan("");
}

}  // namespace

std::string cut_table_csv(const std::vector<CutResult>& cuts) {
  const int flutes = flutes_of(cuts);
  std::string s =
      "file,status,samples,duration_s,in_plane_force_rms_N,in_plane_force_max_N,spindle_rpm,"
      "revolutions,revolutions_cutting,alpha_mean_deg,alpha_std_deg";
  for (int f = 1; f <= flutes; ++f) {
    s += fmt::format(",peak_resultant_N_{}", f);
  }
  s += ",delta_fy_N,residual_rms_fx_N,residual_rms_fy_N,residual_rms_fz_N,alerts,warnings\n";
  for (const auto& c : cuts) {
    const json& j = c.summary;
    std::vector<std::string> fields = {csv_field(c.file),
                                       csv_field(status(c)),
                                       csv_number(at(j, "/samples")),
                                       csv_number(at(j, "/duration_s")),
                                       csv_number(at(j, "/record_in_plane_force_N/rms")),
                                       csv_number(at(j, "/record_in_plane_force_N/max")),
                                       csv_number(at(j, "/spindle_rpm")),
                                       csv_number(at(j, "/revolutions")),
                                       csv_number(at(j, "/revolutions_cutting")),
                                       csv_number(at(j, "/alpha_deg/mean")),
                                       csv_number(at(j, "/alpha_deg/std"))};
    for (int f = 0; f < flutes; ++f) {
      fields.push_back(csv_number(peak(j, f)));
    }
    fields.push_back(csv_number(at(j, "/delta_fy_N")));
    fields.push_back(csv_number(at(j, "/residual_rms_N/fx")));
    fields.push_back(csv_number(at(j, "/residual_rms_N/fy")));
    fields.push_back(csv_number(at(j, "/residual_rms_N/fz")));
    fields.push_back(j.is_object() ? std::to_string(alerts_raised(j)) : std::string());
    fields.push_back(csv_field(j.is_object() ? warning_kinds(j) : std::string()));
    s += fmt::format("{}\n", fmt::join(fields, ","));
  }
  return s;
}

std::string cut_table_text(const std::vector<CutResult>& cuts) {
  const int flutes = flutes_of(cuts);
  std::size_t width = 4;
  for (const auto& c : cuts) {
    width = std::max(width, std::filesystem::path(c.file).filename().string().size());
  }
  auto cell = [](double v, const char* format, int w) {
    return std::isfinite(v) ? fmt::format(fmt::runtime(format), v) : fmt::format("{:>{}}", "—", w);
  };
  std::string s = fmt::format("{:<{}}  {:>9}  {:>5}  {:>10}  {:>15}  {:>{}}  {:>8}  {:>6}  {}\n",
                              "file", width, "rpm", "revs", "|Fxy| rms", "alpha [deg]",
                              fmt::format("peak |Fxy| per flute [N]"), std::max(flutes * 8, 24),
                              "dFy [N]", "alerts", "warnings");
  for (const auto& c : cuts) {
    const json& j = c.summary;
    std::string peaks;
    for (int f = 0; f < flutes; ++f) {
      peaks += cell(peak(j, f), "{:>8.2f}", 8);
    }
    const double a_mean = at(j, "/alpha_deg/mean");
    const std::string alpha = std::isfinite(a_mean)
                                  ? fmt::format("{:.1f} ± {:.1f}", a_mean, at(j, "/alpha_deg/std"))
                                  : std::string("—");
    s += fmt::format("{:<{}}  {}  {}  {}  {:>15}  {:>{}}  {}  {:>6}  {}\n",
                     std::filesystem::path(c.file).filename().string(), width,
                     cell(at(j, "/spindle_rpm"), "{:>9.1f}", 9),
                     cell(at(j, "/revolutions"), "{:>5.0f}", 5),
                     cell(at(j, "/record_in_plane_force_N/rms"), "{:>8.2f} N", 10), alpha, peaks,
                     std::max(flutes * 8, 24), cell(at(j, "/delta_fy_N"), "{:>8.3f}", 8),
                     j.is_object() ? std::to_string(alerts_raised(j)) : std::string("—"),
                     status(c) == "ok" ? warning_kinds(j) : status(c));
    while (s.size() >= 2 && s[s.size() - 2] == ' ') {  // no warnings: no blanks before the end
      s.erase(s.size() - 2, 1);
    }
  }
  return s;
}

}  // namespace millwatch::shell
