#include "replay/calibrate_command.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <complex>
#include <ctime>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/config/json_reader.hpp"
#include "core/identify/calibration.hpp"
#include "core/monitor/monitor_config.hpp"
#include "core/monitor/pipeline.hpp"
#include "core/monitor/run_summary.hpp"
#include "shell/bad_records.hpp"
#include "shell/column_map.hpp"
#include "shell/json_file.hpp"
#include "shell/material_preset.hpp"
#include "shell/monitor_config_file.hpp"
#include "shell/output_file.hpp"
#include "shell/progress_line.hpp"
#include "shell/recording_source.hpp"
#include "shell/shell_sink.hpp"

namespace millwatch::shell {
namespace {

namespace fs = std::filesystem;

/// The shell's log of a cut (lock, bad input) without its alerts: a calibration is not
/// monitoring, and a feed sweep with runout raises the flute-imbalance alert on every cut.
class CalibrationSink : public monitor::PipelineSink {
 public:
  explicit CalibrationSink(ShellSink& log) : log_(log) {}
  void on_revolution(const monitor::RevolutionRecord& r) override { log_.on_revolution(r); }
  void on_sync_average(const monitor::SyncAverage& measured, const monitor::Lockstep* model,
                       std::int64_t revolution, std::int64_t utime_us) override {
    log_.on_sync_average(measured, model, revolution, utime_us);
  }
  void on_spindle(const monitor::SpindleUpdate& u) override { log_.on_spindle(u); }
  void on_event(const monitor::PipelineEvent& e) override { log_.on_event(e); }

 private:
  ShellSink& log_;
};

/// One cut read and monitored.
struct MonitoredCut {
  identify::CalibrationCut cut;
  std::int64_t revolutions = 0;
  double max_unexplained = 0.2;  ///< its configuration's identification.max_unexplained
};

MonitoredCut monitor_cut(const CalibrateOptions& o, const ConfigFile& config_file,
                         std::size_t index, ProgressLine& progress) {
  const fs::path input = o.inputs[index];
  const std::string where = fmt::format("cut {} of {}", index + 1, o.inputs.size());
  if (!fs::exists(input)) {
    throw std::runtime_error(input.string() + ": recording not found (" + where + ")");
  }
  // The cut: its sidecar under --config's overrides (as the replay does), or --config alone.
  if (o.config.empty()) {
    fs::path beside = input;
    if (detect_recording_format(input) == RecordingFormat::kLcmLog ||
        !fs::exists(beside.replace_extension(".json"))) {
      throw std::runtime_error(input.string() + ": no sidecar beside it (" + where +
                               "): describe the cut with --config");
    }
  }
  LoadedMonitorConfig loaded =
      load_monitor_config({input, o.config, "", o.columns, where}, config_file);
  loaded.warn_model_note(input);
  const std::optional<double> sidecar_feed_um = loaded.sidecar_feed_per_tooth_um;
  const fs::path sidecar = loaded.sidecar;
  // The cut's feed per tooth: --feeds-um, else its sidecar; both given must agree.
  double feed_um = 0.0;
  if (!o.feeds_um.empty()) {
    feed_um = o.feeds_um[index];
    if (sidecar_feed_um && std::fabs(*sidecar_feed_um - feed_um) > 1e-6 * feed_um) {
      throw std::runtime_error(
          fmt::format("{}: --feeds-um gives {:g} um per tooth ({}), its sidecar {} says {:g} um",
                      input.string(), feed_um, where, sidecar.string(), *sidecar_feed_um));
    }
  } else if (sidecar_feed_um) {
    feed_um = *sidecar_feed_um;
  } else {
    throw std::runtime_error(input.string() + ": no feed per tooth (" + where +
                             "): no sidecar states it; give --feeds-um, one per cut");
  }
  if (!(feed_um > 0.0)) {
    throw std::runtime_error(fmt::format("{}: feed per tooth {:g} um ({}): must be > 0",
                                         input.string(), feed_um, where));
  }
  if (!o.feeds_um.empty()) {
    take_option_feed(loaded, feed_um, input.string() + " (" + where + ")");
  } else {
    loaded.json["model"]["process"]["feed_per_tooth_um"] = feed_um;
  }
  const double config_rate_hz = configured_rate_hz(loaded);

  BadRecordLog bad(input.string(), detect_recording_format(input));
  RecordingOptions ro;
  ro.columns = loaded.columns;
  ro.config_rate_hz = config_rate_hz;
  ro.on_bad = bad.handler();
  std::unique_ptr<RecordingSource> source = open_recording(input, ro);
  take_recording_rate(loaded, *source, input.string());
  monitor::MonitorConfig config = parse_monitor_config(loaded);
  config.lockstep = false;  // the model is fitted afterwards; no comparison needed meanwhile

  monitor::RunSummary summary(config);
  ShellSink log(summary, input.string());
  identify::CutWindows windows;
  log.set_observer(&windows);
  CalibrationSink sink(log);
  monitor::Pipeline pipeline(config, sink);
  std::int64_t samples = 0;
  while (const std::optional<monitor::SampleBlock> block = source->next(4096)) {
    samples += static_cast<std::int64_t>(block->fx_N.size());
    pipeline.process(*block);
    if (progress.due()) {
      progress.show(fmt::format("calibrate: {}: {:.0f} %  ({:.1f} s)", where,
                                100.0 * source->progress(), progress.elapsed_s()));
    }
  }
  pipeline.finish();
  bad.finish(*source);
  if (samples == 0) {
    throw std::runtime_error(fmt::format("{}: no samples to calibrate on ({}): {}", input.string(),
                                         where, why_no_samples(*source)));
  }
  if (windows.windows().empty() && windows.revolutions() == 0) {
    // Not its length: the monitor measured nothing, and its summary says why (no lock, no
    // cutting heard, a speed outside the search).
    summary.finish(pipeline.status());
    std::string why;
    for (const auto& w : summary.to_json().value("warnings", nlohmann::json::array())) {
      if (w.value("kind", std::string()) != "no identification") {
        why += fmt::format("{} {}: {}", why.empty() ? ":" : ";", w.value("kind", std::string()),
                           w.value("detail", std::string()));
      }
    }
    throw std::runtime_error(fmt::format("{}: no revolution measured to calibrate on ({}){}",
                                         input.string(), where, why));
  }
  if (windows.windows().empty()) {
    throw std::runtime_error(fmt::format(
        "{}: too short to calibrate on ({}): {} revolution(s) measured, one window needs {} "
        "(sync_average.window_revolutions)",
        input.string(), where, windows.revolutions(), config.sync_window_revolutions));
  }
  MonitoredCut out;
  out.revolutions = windows.revolutions();
  out.cut.name = input.string();
  out.cut.model = config.model;
  const signal::ButterworthDesign filter = pipeline.filter();
  out.cut.filter = [filter, zero_phase = config.filter_zero_phase](double hz) {
    const std::complex<double> h = filter.response(hz);
    return zero_phase ? std::complex<double>(std::norm(h), 0.0) : h;
  };
  out.cut.windows = windows.windows();
  out.max_unexplained = config.identification.max_unexplained;
  spdlog::info("{}: {} at {:g} um per tooth: {} windows of {} revolutions", input.string(),
               source->description(), feed_um, out.cut.windows.size(),
               config.sync_window_revolutions);
  return out;
}

std::string num(const nlohmann::json& v, const char* format) {
  return v.is_number() ? fmt::format(fmt::runtime(format), v.get<double>()) : "—";
}

/// The readable report.
std::string report_text(const nlohmann::json& j, const identify::CalibrationResult& r) {
  std::string s;
  const auto& tool = r.joint.fit.config.tool;
  s += fmt::format("calibration over {} cut{}: one tool ({:g} mm, {} flutes), {} law, {}\n",
                   r.cuts.size(), r.cuts.size() == 1 ? "" : "s", tool.diameter_mm, tool.flutes,
                   model::to_string(r.joint.fit.config.material.law),
                   r.tared ? "mean force fitted (channels tared)"
                           : "mean force left out (channels not said to be tared: --tared)");
  s += "  cut                                 f_t um  chip um      rpm  revs  fit residual "
       "fx, fy N   unexplained\n";
  for (const auto& c : j["cuts"]) {
    std::string name = c["name"].get<std::string>();
    if (name.size() > 34) {
      name = "…" + name.substr(name.size() - 33);
    }
    s += fmt::format("  {:<34} {:>7} {:>8} {:>8} {:>5}  {:>9} {:>9}   {:>8}\n", name,
                     num(c["feed_per_tooth_um"], "{:.3f}"), num(c["chip_load_um"], "{:.3f}"),
                     num(c["spindle_rpm"], "{:.0f}"), c["revolutions"].get<int>(),
                     num(c["residual_rms_N"][0], "{:.4f}"), num(c["residual_rms_N"][1], "{:.4f}"),
                     c["unexplained_fraction"].is_number()
                         ? fmt::format("{:.2f} %", 100.0 * c["unexplained_fraction"].get<double>())
                         : "—");
  }
  // The classic regression gives linear-edge coefficients: beside the joint fit's where its law
  // is that one, in a block of their own otherwise (a column of dashes said nothing of why).
  bool side_by_side = false;
  for (const identify::Estimate& e : r.joint.fit.coefficients) {
    side_by_side =
        side_by_side || (j.contains("coefficients") && j["coefficients"].contains(e.name) &&
                         j["coefficients"][e.name]["classic"].is_number());
  }
  s += side_by_side
           ? "\n  coefficient           joint model fit          classic regression (mean force)\n"
           : "\n  coefficient           joint model fit\n";
  for (const identify::Estimate& e : r.joint.fit.coefficients) {  // in the law's order
    if (j.contains("coefficients") && j["coefficients"].contains(e.name)) {
      const std::string& name = e.name;
      const nlohmann::json& v = j["coefficients"][name];
      s += fmt::format("  {:<20} {:>10} ± ", name, num(v["value"], "{:.3f}"));
      s += side_by_side ? fmt::format("{:<9}", num(v["std"], "{:.3f}")) : num(v["std"], "{:.3f}");
      if (side_by_side) {
        s +=
            fmt::format(" {:>10} {}", num(v["classic"], "{:.3f}"),
                        v["classic_std"].is_number() ? "± " + num(v["classic_std"], "{:.3f}") : "");
      }
      s += "\n";
    }
  }
  const nlohmann::json& classic_fit = j["classic"];
  if (!side_by_side && classic_fit.value("ok", false) && classic_fit.contains("coefficients")) {
    s += "\n  classic regression (mean force), linear-edge coefficients (the joint fit's law is "
         "another)\n";
    for (const auto& [name, v] : classic_fit["coefficients"].items()) {
      s += fmt::format("  {:<20} {:>10} ± {}\n", name, num(v["value"], "{:.3f}"),
                       num(v["std"], "{:.3f}"));
    }
  }
  if (j.contains("runout")) {
    const auto& ro = j["runout"];
    s += fmt::format("\n  runout (one for all cuts, at the tool tip)\n");
    const bool lower_bound = ro.value("rho_is_lower_bound", false);
    // The replay's symbols and units, its radii CE1's minus each flute's (summary_text.cpp).
    s += fmt::format("    rho                {}{} ± {} µm{}\n", lower_bound ? "≥ " : "",
                     num(ro["rho_um"], "{:.3f}"), num(ro["rho_std_um"], "{:.3f}"),
                     lower_bound ? " (at a flute's contact edge: a flute cuts nothing beyond it, "
                                   "a lower bound)"
                                 : "");
    s += fmt::format("    gamma              {}° ± {}° (from CE1)\n",
                     num(ro["gamma_deg"], "{:.1f}"), num(ro["gamma_std_deg"], "{:.1f}"));
    for (std::size_t f = 1; f < ro["r_minus_r_ce1_um"].size(); ++f) {
      const nlohmann::json& dr = ro["r_minus_r_ce1_um"][f];
      s += fmt::format("    r_CE1 − r_CE{}      {} ± {} µm\n", f + 1,
                       num(dr.is_number() ? nlohmann::json(-dr.get<double>()) : dr, "{:.3f}"),
                       num(ro["r_minus_r_ce1_std_um"][f], "{:.3f}"));
    }
    s += fmt::format("  flute labelling: {}\n", ro["flute_labelling"].get<std::string>());
  }
  if (j.contains("fit")) {
    const auto& f = j["fit"];
    std::string pairs;
    for (const auto& p : f.value("correlated", nlohmann::json::array())) {
      pairs +=
          (pairs.empty() ? "" : ", ") + p[0].get<std::string>() + "/" + p[1].get<std::string>();
    }
    s += fmt::format(
        "  fit: {} of the measured force unexplained, {} iterations; correlated "
        "(|r| > 0.9): {}\n",
        f["unexplained_fraction"].is_number()
            ? fmt::format("{:.2f} %", 100.0 * f["unexplained_fraction"].get<double>())
            : "—",
        f.value("iterations", 0), pairs.empty() ? "none" : pairs);
  }
  const auto& classic = j["classic"];
  s += fmt::format("  classic regression: {}\n",
                   classic["ok"].get<bool>() ? classic["note"].get<std::string>()
                                             : "none: " + classic["reason"].get<std::string>());
  s += r.warnings.empty() ? "  warnings: none\n" : "  warnings:\n";
  for (const std::string& w : r.warnings) {
    s += "    " + w + "\n";
  }
  return s;
}

std::string utc_now() {
  const std::time_t t = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  gmtime_r(&t, &tm);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return text;
}

}  // namespace

int run_calibrate(const CalibrateOptions& o) {
  if (!o.feeds_um.empty() && o.feeds_um.size() != o.inputs.size()) {
    throw std::runtime_error(
        fmt::format("--feeds-um gives {} feed(s) for {} cut(s): one per cut, "
                    "in the order of the cuts",
                    o.feeds_um.size(), o.inputs.size()));
  }
  if (!o.output.empty()) {  // written last: a path that cannot take it must not cost the fit
    check_output_file("-o", o.output);
  }
  for (std::size_t i = 0; i < o.inputs.size(); ++i) {  // before any cut is read
    if (!fs::exists(o.inputs[i])) {
      throw std::runtime_error(fmt::format("{}: recording not found (cut {} of {})", o.inputs[i],
                                           i + 1, o.inputs.size()));
    }
  }
  const ConfigFile config_file = read_config_file(o.config);
  std::vector<identify::CalibrationCut> cuts;
  ProgressLine progress(o.progress, 0.0, 0.25);
  identify::CalibrationOptions options;
  options.tared = o.tared;
  for (std::size_t i = 0; i < o.inputs.size(); ++i) {
    MonitoredCut m = monitor_cut(o, config_file, i, progress);
    // The strictest of the cuts' configurations (one, as a rule: --config's or the sidecars').
    options.max_unexplained_variance =
        i == 0 ? m.max_unexplained : std::min(options.max_unexplained_variance, m.max_unexplained);
    cuts.push_back(std::move(m.cut));
  }
  identify::CalibrationResult r;
  progress.show(fmt::format("calibrate: fitting {} cuts jointly  ({:.1f} s)", cuts.size(),
                            progress.elapsed_s()));
  try {
    r = identify::calibrate(cuts, options);
  } catch (const std::invalid_argument& e) {
    progress.done();
    throw std::runtime_error(e.what());
  }
  progress.done();
  if (!r.ok) {
    throw std::runtime_error("calibration failed: " + r.message);
  }
  for (const std::string& w : r.warnings) {
    spdlog::warn("calibration: {}", w);
  }
  const nlohmann::json j = identify::to_json(r);
  if (!o.output.empty()) {
    nlohmann::json provenance = {
        {"date", utc_now()},
        {"config", o.config.empty() ? nlohmann::json(nullptr) : nlohmann::json(o.config)},
        {"tool", model::to_json(r.joint.fit.config)["tool"]}};
    const std::string name = !o.name.empty()
                                 ? o.name
                                 : fmt::format("calibrated on {} cut{} ({})", cuts.size(),
                                               cuts.size() == 1 ? "" : "s", utc_now());
    write_text_file(o.output, identify::material_preset(r, name, provenance).dump(2) + "\n");
  }
  if (o.json) {
    std::printf("%s\n", j.dump(2).c_str());
  } else {
    std::printf("%s", report_text(j, r).c_str());
    if (!o.output.empty()) {
      std::printf(
          "  material preset written to %s (\"model\": {\"material\": \"%s\"} in a "
          "configuration)\n",
          o.output.c_str(), fs::path(o.output).filename().c_str());
    }
  }
  std::fflush(stdout);
  return 0;
}

}  // namespace millwatch::shell
