#include "replay/diagnose_command.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/config/json_reader.hpp"
#include "core/diagnose/across_feeds.hpp"
#include "core/diagnose/diagnosis.hpp"
#include "core/monitor/monitor_config.hpp"
#include "shell/bad_records.hpp"
#include "shell/diagnosis_report.hpp"
#include "shell/monitor_config_file.hpp"
#include "shell/output_file.hpp"
#include "shell/progress_line.hpp"
#include "shell/recording_source.hpp"

namespace millwatch::shell {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> split_names(const std::string& list) {
  std::vector<std::string> out;
  std::stringstream ss(list);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (!item.empty()) {
      out.push_back(item);
    }
  }
  return out;
}

/// A cut read for the diagnosis: its record in the model frame and its starting model.
struct LoadedCut {
  std::string input;
  std::string config_name;
  diagnose::CutRecord record;
  model::ModelConfig start;
};

LoadedCut load_cut(const DiagnoseCliOptions& o, const ConfigFile& file, std::size_t index) {
  const fs::path input = o.inputs[index];
  const bool several = o.inputs.size() > 1;
  const std::string where =
      several ? fmt::format("cut {} of {}", index + 1, o.inputs.size()) : std::string();
  if (!fs::exists(input)) {
    throw std::runtime_error(input.string() + ": no such recording" +
                             (several ? " (" + where + ")" : ""));
  }
  LoadedMonitorConfig loaded = load_monitor_config({input, o.config, o.sidecar, "", where}, file);
  loaded.warn_model_note(input);
  // The cut's feed per tooth: --feeds-um, else its sidecar, else --config's; both --feeds-um and
  // a sidecar given must agree. Across feeds each cut's own feed is needed.
  if (!o.feeds_um.empty()) {
    const double f = o.feeds_um[index];
    if (!(f > 0.0)) {
      throw std::runtime_error(
          fmt::format("--feeds-um: {:g} um per tooth for {}: must be > 0", f, input.string()));
    }
    if (loaded.sidecar_feed_per_tooth_um &&
        std::fabs(*loaded.sidecar_feed_per_tooth_um - f) > 1e-6 * f) {
      throw std::runtime_error(fmt::format(
          "{}: --feeds-um gives {:g} um per tooth, its sidecar {} says {:g} um", input.string(), f,
          loaded.sidecar.string(), *loaded.sidecar_feed_per_tooth_um));
    }
    take_option_feed(loaded, f, several ? input.string() + " (" + where + ")" : input.string());
  } else if (loaded.sidecar_feed_per_tooth_um) {
    // The cut's own feed wins over --config's (several cuts share one --config).
    loaded.json["model"]["process"]["feed_per_tooth_um"] = *loaded.sidecar_feed_per_tooth_um;
  } else if (several) {
    throw std::runtime_error(input.string() + ": no feed per tooth (" + where +
                             "): no sidecar states it; give --feeds-um, one per cut");
  }
  BadRecordLog bad(input.string(), detect_recording_format(input));
  RecordingOptions ro;
  ro.columns = loaded.columns;
  ro.config_rate_hz = configured_rate_hz(loaded);
  ro.on_bad = bad.handler();
  auto source = open_recording(input, ro);
  spdlog::info("{}: {}", input.string(), source->description());
  take_recording_rate(loaded, *source, input.string());
  // The monitor's low-pass plays no part here (the diagnosis compares its own band): unless
  // configured, it is set where the monitor's checks against the tooth-passing frequency pass.
  const double rate_hz = loaded.config_rate_hz();  // checked above, the recording's now
  nlohmann::json& base = loaded.json;
  if (rate_hz > 0.0 && base.is_object() &&
      !(base.contains("filter") && base["filter"].is_object() &&
        base["filter"].contains("cutoff_hz"))) {
    base["filter"]["cutoff_hz"] = 0.4 * rate_hz;
  }
  const monitor::MonitorConfig config = parse_monitor_config(loaded);

  // The record in the model frame, trimmed to [--from-s, --to-s) in seconds from its first
  // sample, along the recording's own clock (an LCM log's is the epoch's). The model is fitted
  // along an unbroken time base: a gap or a sample that is not a number within the stretch
  // stops the diagnosis, saying where, after the bad records read up to there are counted.
  LoadedCut cut;
  cut.input = input.string();
  cut.config_name = loaded.name;
  double rate = 0.0;
  double last_t = 0.0;
  double end_t = 0.0;  // after the record's last sample
  std::int64_t first_us = 0;
  std::string stopped;  // why the stretch cannot be diagnosed, if it cannot
  while (stopped.empty()) {
    auto block = source->next(65536);
    if (!block) {
      break;
    }
    if (rate <= 0.0) {
      rate = block->sample_rate_hz;
      first_us = block->utime_us;
    }
    const double t0 = static_cast<double>(block->utime_us - first_us) * 1e-6;
    end_t = t0 + static_cast<double>(block->fx_N.size()) / rate;
    for (std::size_t i = 0; i < block->fx_N.size(); ++i) {
      const double t = t0 + static_cast<double>(i) / rate;
      if (t < o.from_s || (o.to_s > 0.0 && t >= o.to_s)) {
        continue;
      }
      if (!cut.record.force_N[0].empty() && t - last_t > 1.5 / rate) {
        stopped = fmt::format(
            "{}: {} sample(s) missing between {:.6f} s and {:.6f} s from the record's first "
            "sample: the diagnosis needs an unbroken record; choose a stretch without the gap "
            "with --from-s/--to-s",
            input.string(), std::llround((t - last_t) * rate) - 1, last_t, t);
        break;
      }
      if (!std::isfinite(block->fx_N[i]) || !std::isfinite(block->fy_N[i]) ||
          !std::isfinite(block->fz_N[i])) {
        stopped = fmt::format(
            "{}: the sample {:.6f} s from the record's first is not a finite number: choose a "
            "stretch without it with --from-s/--to-s",
            input.string(), t);
        break;
      }
      const auto f = config.axis_map.to_model({block->fx_N[i], block->fy_N[i], block->fz_N[i]});
      cut.record.force_N[0].push_back(f[0]);
      cut.record.force_N[1].push_back(f[1]);
      last_t = t;
    }
  }
  bad.finish(*source);
  if (!stopped.empty()) {
    throw std::runtime_error(stopped);
  }
  if (rate <= 0.0 || (cut.record.force_N[0].empty() && o.from_s <= 0.0 && o.to_s <= 0.0)) {
    throw std::runtime_error(input.string() +
                             ": no samples to diagnose: " + why_no_samples(*source));
  }
  if (cut.record.force_N[0].empty()) {
    throw std::runtime_error(fmt::format(
        "{}: no samples to diagnose within --from-s/--to-s (the record spans {:.6f} s from its "
        "first sample)",
        input.string(), end_t));
  }
  cut.record.sample_rate_hz = rate;
  cut.start = config.model;
  if (o.start == "plain") {
    cut.start = diagnose::plain_model(cut.start);
  }
  return cut;
}

diagnose::Diagnosis diagnose_cut(const DiagnoseCliOptions& o, const LoadedCut& cut,
                                 ProgressLine& progress, const std::string& prefix) {
  diagnose::DiagnoseOptions options;
  options.band_hz = o.band_hz;
  options.max_steps = o.max_steps;
  options.max_exchanges = o.exchanges;
  options.jobs = o.jobs;
  options.candidates = split_names(o.candidates);
  options.progress = [&](std::string_view line) {
    progress.show(fmt::format("diagnose: {}{}  ({:.1f} s)", prefix, line, progress.elapsed_s()));
  };
  diagnose::Diagnosis d;
  try {
    d = diagnose::diagnose(cut.record, cut.start, options);
  } catch (const config::ConfigError& e) {
    progress.done();
    throw std::runtime_error(cut.config_name + ": " + e.what());
  } catch (const std::invalid_argument& e) {
    progress.done();
    throw std::runtime_error(cut.input + ": " + e.what());
  }
  progress.done();
  if (!d.ok) {
    throw std::runtime_error(cut.input + ": " + d.message);
  }
  return d;
}

void print_steps(const diagnose::Diagnosis& d) {
  std::printf("  start: residual %.4f, %.4f N (noise floor %.4f, %.4f N)\n",
              d.initial.residual_rms_N[0], d.initial.residual_rms_N[1], d.noise_floor_N[0],
              d.noise_floor_N[1]);
  for (const auto& s : d.steps) {
    std::printf(
        "  + %-22s residual %.4f, %.4f N  ΔBIC %.1f%s\n", s.added.c_str(), s.residual_rms_N[0],
        s.residual_rms_N[1], s.gain,
        s.runner_up.empty()
            ? ""
            : fmt::format(" (over {} by {:.1f})", s.runner_up, s.margin_over_runner_up).c_str());
    if (!s.removed.empty()) {
      std::printf("    in place of %s: the exchange gains ΔBIC %.1f%s\n", s.removed.c_str(),
                  s.exchange_gain, s.exchange_steps == 2 ? " with the step after it" : "");
    }
  }
  for (const auto& note : d.final_notes) {
    std::printf("  %s\n", note.c_str());
  }
  for (const auto& p : d.at_bound) {
    std::printf("  %s held at its %s physical bound %g (the fit wanted a value beyond it)\n",
                p.name.c_str(), p.at_bound.c_str(), p.value);
  }
}

}  // namespace

int run_diagnose(const DiagnoseCliOptions& o) {
  if (o.max_steps < 0) {
    throw std::runtime_error(fmt::format("--max-steps: {} is negative", o.max_steps));
  }
  if (o.exchanges < 0) {
    throw std::runtime_error(fmt::format("--exchanges: {} is negative", o.exchanges));
  }
  if (o.start != "plain" && o.start != "configured") {
    throw std::runtime_error("--start: '" + o.start + "' is neither 'plain' nor 'configured'");
  }
  const bool several = o.inputs.size() > 1;
  if (several && !o.sidecar.empty()) {
    throw std::runtime_error(
        "--sidecar describes one cut: with several, each cut's CUT.json beside it (or --config "
        "and --feeds-um) describes it");
  }
  if (!o.feeds_um.empty() && o.feeds_um.size() != o.inputs.size()) {
    throw std::runtime_error(fmt::format(
        "--feeds-um gives {} feed(s) for {} cut(s): one per cut, in the order of the cuts",
        o.feeds_um.size(), o.inputs.size()));
  }
  if (o.to_s > 0.0 && o.to_s <= o.from_s) {  // an empty stretch, whatever the record
    throw std::runtime_error(
        fmt::format("--to-s {:g} is not after --from-s {:g}", o.to_s, o.from_s));
  }
  // The report is written last: a path that cannot take it must not cost the whole diagnosis.
  std::error_code report_ec;
  fs::create_directories(o.report, report_ec);
  if (report_ec) {
    throw std::runtime_error("--report " + o.report + ": cannot make the report folder (" +
                             report_ec.message() + ")");
  }
  const ConfigFile file = read_config_file(o.config);
  ProgressLine progress(o.progress);
  if (!several) {
    const LoadedCut cut = load_cut(o, file, 0);
    const diagnose::Diagnosis d = diagnose_cut(o, cut, progress, "");
    const ReportFiles files =
        write_diagnosis_report(d, o.report, fs::path(cut.input).filename().string(), o.plots);
    if (!files.plot_problem.empty() && o.plots) {
      spdlog::warn("plots left out: {}", files.plot_problem);
    }
    std::printf("%s\n", d.verdict.c_str());
    print_steps(d);
    std::printf("  report: %s\n", (fs::path(o.report) / "report.md").string().c_str());
    return 0;
  }
  // Several cuts: each read and diagnosed in turn (its report in DIR/<stem>/), then compared.
  std::vector<LoadedCut> cuts;
  for (std::size_t i = 0; i < o.inputs.size(); ++i) {  // every cut read before the long work
    cuts.push_back(load_cut(o, file, i));
  }
  const std::vector<std::string> stems = shell::unique_stems(o.inputs);
  std::vector<diagnose::Diagnosis> diagnoses;
  diagnoses.reserve(cuts.size());
  for (std::size_t i = 0; i < cuts.size(); ++i) {
    diagnoses.push_back(
        diagnose_cut(o, cuts[i], progress, fmt::format("cut {}/{}: ", i + 1, cuts.size())));
    cuts[i].record = {};  // its samples are no longer needed
    const ReportFiles files =
        write_diagnosis_report(diagnoses.back(), fs::path(o.report) / stems[i],
                               fs::path(cuts[i].input).filename().string(), o.plots);
    if (!files.plot_problem.empty() && o.plots) {
      spdlog::warn("{}: plots left out: {}", cuts[i].input, files.plot_problem);
    }
  }
  std::vector<diagnose::FeedCut> feed_cuts;
  std::vector<CutReport> reports;
  for (std::size_t i = 0; i < cuts.size(); ++i) {
    const std::string name = fs::path(cuts[i].input).filename().string();
    feed_cuts.push_back({name, cuts[i].start.process.feed_per_tooth_um, &diagnoses[i]});
    reports.push_back({name, stems[i], &diagnoses[i]});
  }
  const diagnose::AcrossFeeds across = diagnose::across_feeds(feed_cuts);
  const ReportFiles files = write_across_feeds_report(across, reports, o.report, o.plots);
  if (!files.plot_problem.empty() && o.plots) {
    spdlog::warn("plot left out: {}", files.plot_problem);
  }
  std::printf("%s\n  %s\n", across.verdict.c_str(), across.trend.sentence.c_str());
  std::printf("  %-28s %7s  %-19s %-19s %s\n", "cut", "f_t um", "residual before N",
              "residual after N", "named");
  for (const auto& c : across.cuts) {
    std::string named;
    for (const auto& e : c.named_effects) {
      named += (named.empty() ? "" : ", ") + e;
    }
    std::printf("  %-28s %7.3g  %8.4f, %8.4f  %8.4f, %8.4f  %s\n", c.name.c_str(),
                c.feed_per_tooth_um, c.before.total_N[0], c.before.total_N[1], c.after.total_N[0],
                c.after.total_N[1], named.empty() ? "-" : named.c_str());
  }
  std::printf("  report: %s\n", (fs::path(o.report) / "report.md").string().c_str());
  return 0;
}

}  // namespace millwatch::shell
