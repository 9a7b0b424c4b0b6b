#include "core/monitor/run_summary.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>

#include "core/config/json_reader.hpp"
#include "core/model/steady_state.hpp"

namespace millwatch::monitor {
namespace {

/// NaN serialises as null in JSON: say "no data" honestly.
nlohmann::json number_or_null(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
}

/// The lockstep model's steady states over the run's builds (PipelineStatus), with what of
/// them was approximate in words (notes: empty when every build was exact).
nlohmann::json model_steady_state(const PipelineStatus& s) {
  nlohmann::json notes = nlohmann::json::array();
  std::array<char, 400> text{};
  if (s.model_builds_unsettled > 0) {
    std::snprintf(text.data(), text.size(),
                  "%lld of %lld model builds had slots (disc, immersion) whose accumulation did "
                  "not repeat within %d revolutions (%d of %d slots in one build): their state "
                  "at the last of them stands in the model revolution, which is approximate there",
                  static_cast<long long>(s.model_builds_unsettled),
                  static_cast<long long>(s.model_builds), model::kMaxSlotRevolutions,
                  s.model_unsettled_slots_most, s.model_slots_of_most);
    notes.push_back(text.data());
  }
  if (s.model_builds_area_unsettled > 0) {
    std::snprintf(text.data(), text.size(),
                  "%lld of %lld model builds stopped before the ploughed areas and the tool's "
                  "deflection settled together: their last solution stands",
                  static_cast<long long>(s.model_builds_area_unsettled),
                  static_cast<long long>(s.model_builds));
    notes.push_back(text.data());
  }
  return {{"builds_with_unsettled_slots", s.model_builds_unsettled},
          {"unsettled_slots_most", s.model_unsettled_slots_most},
          {"slots_of_that_build", s.model_slots_of_most},
          {"builds_with_areas_unsettled", s.model_builds_area_unsettled},
          {"notes", notes}};
}

}  // namespace

double RunSummary::Running::mean() const {
  return n > 0 ? sum / static_cast<double>(n) : std::numeric_limits<double>::quiet_NaN();
}

double RunSummary::Running::stddev() const {
  if (n < 2) {
    return std::numeric_limits<double>::quiet_NaN();  // one value has no spread to state
  }
  const double m = mean();
  return std::sqrt(
      std::max(0.0, (sum_sq - static_cast<double>(n) * m * m) / static_cast<double>(n - 1)));
}

double RunSummary::Running::rms() const {
  return n > 0 ? std::sqrt(sum_sq / static_cast<double>(n))
               : std::numeric_limits<double>::quiet_NaN();
}

RunSummary::RunSummary(const MonitorConfig& config)
    : config_(config), flutes_(config.model.tool.flutes) {}

void RunSummary::add(const RevolutionRecord& r) {
  if (revolutions_ == 0) {
    first_revolution_utime_us_ = r.utime_us;
  }
  last_revolution_utime_us_ = r.utime_us;
  ++revolutions_;
  if (r.spindle_rpm > 0.0) {  // 0: not measured
    rpm_.add(r.spindle_rpm);
  }
  const auto& m = r.measured;
  if (!m.bounded) {
    return;
  }
  // Bounded (both CE1 events found): each flute's force window is known, even when a flute in
  // between did not cut. Valid (every event found): its periods and α are known too.
  ++bounded_;
  FluteStatistics& f = since_lock_;
  for (int j = 0; j < flutes_; ++j) {
    const auto uj = static_cast<std::size_t>(j);
    for (std::size_t a = 0; a < 3; ++a) {
      f.peak[uj][a].add(m.peak_N[uj][a]);
    }
    f.peak_resultant[uj].add(m.peak_resultant_N[uj]);
  }
  if (m.valid) {
    ++valid_;
    f.alpha.add(m.alpha_deg);
    f.delta_fy.add(m.delta_fy_N);
    for (int j = 0; j < flutes_; ++j) {
      f.period[static_cast<std::size_t>(j)].add(m.flute_period_s[static_cast<std::size_t>(j)]);
    }
  }
  if (r.model_valid) {
    if (r.model.valid && m.valid) {
      f.model_alpha.add(r.model.alpha_deg);
      f.model_delta_fy.add(r.model.delta_fy_N);
    }
    for (std::size_t a = 0; a < 3; ++a) {
      residual_[a].sum_sq += r.residual_rms_N[a] * r.residual_rms_N[a];
      ++residual_[a].n;
    }
    measured_rms_.sum_sq += r.measured_rms_N * r.measured_rms_N;
    ++measured_rms_.n;
  }
}

void RunSummary::add(const SpindleUpdate& u) {
  if (u.estimate.valid) {
    tracker_rpm_.add(u.estimate.spindle_rpm);
  }
}

void RunSummary::add(const Alert& a) {
  alerts_.push_back({{"kind", std::string(to_string(a.kind))},
                     {"active", a.active},
                     {"severity", static_cast<int>(a.severity)},
                     {"utime", a.utime_us},
                     {"revolution", a.revolution},
                     {"value", a.value},
                     {"threshold", a.threshold},
                     {"quantity", std::string(a.quantity)},
                     {"message", std::string(a.message.data())}});
}

void RunSummary::add(const PipelineEvent& e) {
  if (e.kind == PipelineEventKind::kLockAcquired) {
    kept_.merge(since_lock_);  // the last lock's labelling held to its end
    since_lock_ = {};
  }
  switch (e.kind) {
    case PipelineEventKind::kLockAcquired:
    case PipelineEventKind::kLockLost:
    case PipelineEventKind::kModelAligned:
    case PipelineEventKind::kModelUpdated:
    case PipelineEventKind::kCuttingStopped:
    case PipelineEventKind::kCuttingResumed:
    case PipelineEventKind::kAlertsArmed:
    case PipelineEventKind::kAlertsHeld:  // counted in the status: its own warning
      return;                             // normal operation, not a warning
    default:
      break;
  }
  const std::string kind(to_string(e.kind));
  std::string detail(e.detail);
  if (e.kind == PipelineEventKind::kRecordTooShort) {
    char text[96];
    std::snprintf(text, sizeof text, "%.4f s of samples, %.4f s needed: ",
                  static_cast<double>(e.count) / config_.sample_rate_hz, e.value);
    detail = text + detail;
  } else if (e.kind == PipelineEventKind::kNoSteadySignal && e.count > 0) {
    detail = std::to_string(e.count) + " tracker windows: " + detail;
  } else if (e.kind == PipelineEventKind::kSpeedOutOfRange) {
    detail = describe_line_outside_search(e, config_);
  } else if (e.kind == PipelineEventKind::kFlutesRelabelled) {
    // The lock's revolutions state α, ΔFy and each flute's force from another edge than the
    // relabelled CE1's: left out (the earlier locks' stay).
    relabelled_out_ += since_lock_.alpha.n;
    since_lock_ = {};
    char text[640];
    std::snprintf(text, sizeof text,
                  "after %lld revolutions, flute %lld held %.2f times CE1's peak |Fxy| over the "
                  "windows since the lock (the lock's revolutions were unlike the cut: a knock, "
                  "a chip carried?): locked again, its template choosing CE1; alpha, tooth "
                  "periods, flute peaks and ΔFy leave out that lock's revolutions (%lld valid "
                  "revolutions in all so far)",
                  static_cast<long long>(revolutions_), static_cast<long long>(e.count), e.value,
                  static_cast<long long>(relabelled_out_));
    detail = text;
  }
  // The warning's samples: events that count samples (a lost block, a gap, bad samples, a short
  // record), not windows or flutes.
  const bool counts_samples = e.kind != PipelineEventKind::kNoSteadySignal &&
                              e.kind != PipelineEventKind::kSpeedOutOfRange &&
                              e.kind != PipelineEventKind::kFlutesRelabelled;
  auto it = std::find_if(warnings_.begin(), warnings_.end(),
                         [&](const Warning& w) { return w.kind == kind; });
  if (it == warnings_.end()) {
    warnings_.push_back({kind, 0, 0, e.utime_us, detail});
    it = warnings_.end() - 1;
  }
  ++it->occurrences;
  it->samples += counts_samples ? e.count : 0;
}

void RunSummary::finish(const PipelineStatus& status) {
  status_ = status;
}

void RunSummary::reconfigure(const MonitorConfig& config, std::int64_t revolution,
                             std::int64_t utime_us, std::int64_t samples_before) {
  if (config.sample_rate_hz != config_.sample_rate_hz) {
    duration_before_s_ +=
        static_cast<double>(samples_before - samples_at_rate_change_) / config_.sample_rate_hz;
    samples_at_rate_change_ = samples_before;
    notes_.push_back(
        {"rate changed", 1, 0, utime_us,
         "sample_rate_hz " + config::format_number(config_.sample_rate_hz) + " → " +
             config::format_number(config.sample_rate_hz) + " Hz on a reload at revolution " +
             std::to_string(revolution) +
             ": the duration sums each rate's samples at their own rate; a stream still at the "
             "old rate is refused (blocks rejected)"});
  }
  const int flutes = config.model.tool.flutes;
  if (flutes != flutes_) {
    kept_ = {};  // one tool's flutes are not another's
    since_lock_ = {};
    measured_rms_ = Running{};
    residual_ = {};
    warnings_.push_back({"tool changed", 1, 0, utime_us,
                         "monitor.model.tool.flutes " + std::to_string(flutes_) + " → " +
                             std::to_string(flutes) + " on a reload at revolution " +
                             std::to_string(revolution) +
                             ": alpha, tooth periods, peaks, ΔFy and residuals cover the "
                             "revolutions since"});
  }
  config_ = config;
  flutes_ = flutes;
}

void RunSummary::FluteStatistics::merge(const FluteStatistics& o) {
  for (auto [to, from] :
       {std::pair{&alpha, &o.alpha}, std::pair{&delta_fy, &o.delta_fy},
        std::pair{&model_alpha, &o.model_alpha}, std::pair{&model_delta_fy, &o.model_delta_fy}}) {
    to->merge(*from);
  }
  for (std::size_t j = 0; j < kMaxFlutes; ++j) {
    period[j].merge(o.period[j]);
    peak_resultant[j].merge(o.peak_resultant[j]);
    for (std::size_t a = 0; a < 3; ++a) {
      peak[j][a].merge(o.peak[j][a]);
    }
  }
}

RunSummary::FluteStatistics RunSummary::flute_statistics() const {
  FluteStatistics f = kept_;
  f.merge(since_lock_);
  return f;
}

void RunSummary::warn_flute_labelling(const FluteStatistics& f) const {
  // Flute 0 is CE1, the flute whose period holds the largest force, chosen at the lock on its
  // template's revolutions. Revolutions there unlike the rest of the cut (a knock, a chip
  // carried for a while), or a runout change since, can leave another flute holding the larger
  // force for most of the record: α and ΔFy then come from the other edge (for two flutes,
  // CE1's are 360° − α and −ΔFy). Said beyond kFluteLabellingMargin, as the pipeline relabels.
  constexpr std::int64_t kFewest = 10;
  const Running& ce1 = f.peak_resultant[0];
  if (flutes_ < 2 || ce1.n < kFewest) {
    return;
  }
  std::size_t strongest = 0;
  for (std::size_t j = 1; j < static_cast<std::size_t>(flutes_); ++j) {
    if (f.peak_resultant[j].n >= kFewest &&
        f.peak_resultant[j].mean() > f.peak_resultant[strongest].mean()) {
      strongest = j;
    }
  }
  if (strongest == 0 ||
      !(f.peak_resultant[strongest].mean() > kFluteLabellingMargin * ce1.mean())) {
    return;
  }
  std::array<char, 512> text{};
  std::snprintf(text.data(), text.size(),
                "flute %zu's period holds a larger force than flute 1's over the record (mean "
                "peak |Fxy| %.3g N against %.3g N), but flute 1 is CE1, the flute with the "
                "largest force at the lock: the cut there was unlike the rest of the record (a "
                "knock or a chip carried at the lock, or a runout change since?), and α and ΔFy "
                "are stated from another edge than CE1%s",
                strongest + 1, f.peak_resultant[strongest].mean(), ce1.mean(),
                flutes_ == 2 ? " (CE1's are 360° − α and −ΔFy)" : "");
  warn("flute labelling", text.data());
}

void RunSummary::warn(const std::string& kind, const std::string& detail) const {
  derived_.push_back({kind, 1, 0, status_.utime_us, detail});
}

nlohmann::json RunSummary::to_json() const {
  using nlohmann::json;
  derived_.clear();
  const FluteStatistics f = flute_statistics();
  // Each flute's mean, and beside it its spread from revolution to revolution (as α's and ΔFy's).
  constexpr std::array<const char*, 4> kPeakAxes = {"fx", "fy", "fz", "resultant"};
  json periods = json::array(), periods_std = json::array();
  json peak = json::object(), peak_std = json::object();
  for (const char* axis : kPeakAxes) {
    peak[axis] = json::array();
    peak_std[axis] = json::array();
  }
  for (int j = 0; j < flutes_; ++j) {
    const auto uj = static_cast<std::size_t>(j);
    periods.push_back(number_or_null(f.period[uj].mean()));
    periods_std.push_back(number_or_null(f.period[uj].stddev()));
    const std::array<const Running*, 4> of = {&f.peak[uj][0], &f.peak[uj][1], &f.peak[uj][2],
                                              &f.peak_resultant[uj]};
    for (std::size_t a = 0; a < kPeakAxes.size(); ++a) {
      peak[kPeakAxes[a]].push_back(number_or_null(of[a]->mean()));
      peak_std[kPeakAxes[a]].push_back(number_or_null(of[a]->stddev()));
    }
  }
  const auto& in = status_.input;
  const std::int64_t samples = in.samples_accepted;

  // The speed: the revolutions' own, else the tracker's consistent windows, else none.
  double rpm = rpm_.mean();
  std::string rpm_source = "revolutions";
  if (rpm_.n == 0) {
    rpm = tracker_rpm_.mean();
    rpm_source = tracker_rpm_.n > 0 ? "spindle tracker" : "none";
  }
  const bool explained = !warnings_.empty();  // the pipeline said why nothing was measured
  if (revolutions_ == 0 && samples > 0 && !explained) {
    warn("no revolutions", "no revolution was measured; α, periods and peaks are absent");
  } else if (bounded_ > 0 && 10 * valid_ < 9 * bounded_) {  // more than a tenth lost
    warn("flute events missing",
         std::to_string(bounded_ - valid_) + " of " + std::to_string(bounded_) +
             " revolutions had a flute without its tooth event (a flute that does not cut, or "
             "its valley not found): their peaks count, their periods and α do not" +
             (valid_ == 0 ? "; α, ΔFy and periods are absent" : ""));
  } else if (revolutions_ > 0 && bounded_ == 0) {
    warn("no revolutions", "no revolution had its bounds (the CE1 events) found");
  }
  if (revolutions_ > 0 && status_.cutting_revolutions > 0.0 &&
      static_cast<double>(revolutions_ + status_.idle_revolutions) <
          0.9 * status_.cutting_revolutions - 2.0) {
    warn("revolutions missed",
         std::to_string(revolutions_) + " revolutions measured of about " +
             std::to_string(std::llround(status_.cutting_revolutions)) +
             " turned while the tracker heard cutting (the others: before a lock, in gaps, or "
             "without their tooth events)");
  }
  // More revolutions than the spindle turned between the first and the last (at the tracker's
  // speed, not theirs): the tooth events counted features that are not the flutes' (each
  // revolution's speed, periods and α with them). Not the turns heard while cutting: the events
  // measure on through windows too weak for the tracker to call cutting.
  const double turned =
      tracker_rpm_.n > 0
          ? 1.0 + 1e-6 *
                      static_cast<double>(last_revolution_utime_us_ - first_revolution_utime_us_) *
                      tracker_rpm_.mean() / 60.0
          : 0.0;
  if (turned > 0.0 && static_cast<double>(revolutions_) > 1.1 * turned + 2.0) {
    warn("revolutions over-counted",
         std::to_string(revolutions_) + " revolutions measured where the spindle turned about " +
             std::to_string(std::llround(turned)) +
             " (at the tracker's speed): the tooth events followed features that are not the "
             "flutes' (a dead or swapped channel?); their speeds, periods and α are not the "
             "cut's");
  }
  warn_flute_labelling(f);
  if (status_.alert_held_revolutions > 0) {
    std::array<char, 384> text{};
    std::snprintf(
        text.data(), text.size(),
        "%lld revolutions ran more than alerts.conditions_tolerance (%g %%) off the speed "
        "of the flute forces' baseline, at another feed per tooth: runout change and "
        "wear drift did not compare them (breakage did); a new baseline forms once the "
        "speed holds for %d revolutions",
        static_cast<long long>(status_.alert_held_revolutions),
        100.0 * config_.alerts.conditions_tolerance,
        config_.alerts.block_revolutions * config_.alerts.baseline_blocks);
    warn("alerts held", text.data());
  }
  if (config_.lockstep && revolutions_ > 0 && residual_[0].n == 0) {
    warn("no model residuals",
         "the lockstep model was never aligned with the measured revolutions");
  } else if (config_.lockstep && flutes_ >= 2 && f.alpha.n > 0 && f.model_alpha.n == 0) {
    // Its residuals are there, its features not (model.alpha_deg and delta_fy_N null).
    warn("no model alpha",
         "the lockstep model's tooth events were found on none of the " +
             std::to_string(f.alpha.n) +
             " revolutions measured: its α and ΔFy are absent (its force has no tooth-passing "
             "feature the measured template finds: check the model's coefficients and cut)");
  }
  if (flutes_ < 2) {
    // With one flute α is 360° and ΔFy 0 by definition [000]: they say nothing of the cut.
    warn("no alpha", "one flute: α and ΔFy compare two cutting edges");
  } else if (f.alpha.n > 0 && f.alpha.n < config_.alpha_window_revolutions) {
    warn("short window", "α and ΔFy are averaged over " + std::to_string(f.alpha.n) +
                             " revolutions, fewer than tooth_periods.window_revolutions (" +
                             std::to_string(config_.alpha_window_revolutions) + ")");
  }
  if (identification_.is_null() && !identification_off_.empty()) {
    warn("no identification", "identification is off (" + identification_off_ +
                                  "): runout and coefficients are not estimated");
  } else if (identification_.is_null()) {
    warn("no identification",
         "no window of revolutions was fitted (runout and coefficients "
         "need one full synchronous-average window of measured revolutions)");
  } else if (!identification_.contains("runout")) {
    warn("no identification", "the fit of the last window failed: " +
                                  identification_["fit"].value("reason", std::string("?")));
  } else if (const double u = identification_["fit"].value("unexplained_fraction", 1.0);
             u * u > config_.identification.max_unexplained) {
    // The model in lockstep's test (Pipeline::take_identification): the variance unexplained.
    warn("model does not fit",
         "the identified model leaves " + std::to_string(std::lround(100.0 * u)) +
             " % of the measured force unexplained (RMS; " +
             std::to_string(std::lround(100.0 * u * u)) + " % of its variance, above " +
             "identification.max_unexplained " +
             std::to_string(std::lround(100.0 * config_.identification.max_unexplained)) +
             " %): runout and coefficients describe this cut poorly — check the tool and cut "
             "configured (flutes, diameter, feed, depths), or name the missing effect with "
             "millwatch diagnose");
  }
  const bool scattered = identification_.is_object() && identification_.contains("fit") &&
                         identification_["fit"].contains("window_scatter");
  const json spread = scattered ? identification_["fit"]["window_scatter"] : json::object();
  if (scattered && spread.value("widened", false)) {
    std::array<char, 320> text{};
    std::snprintf(text.data(), text.size(),
                  "successive windows' runout estimates scatter more than one window's σ says "
                  "(ρ by %.3f µm, γ by %.1f° from window to window over %d windows): the σ given "
                  "are at least that scatter; the force pins this runout poorly",
                  spread.value("rho_std_um", 0.0), spread.value("gamma_std_deg", 0.0),
                  spread.value("windows", 0));
    warn("runout scatters", text.data());
  }
  if (scattered && spread.value("widened_by_drift", false)) {
    std::array<char, 480> text{};
    std::snprintf(text.data(), text.size(),
                  "ρ moved by %+.3f µm (γ by %+.1f°) from the oldest quarter of the last %d "
                  "windows to the newest, while the radius differences moved by %.3f µm at "
                  "most: ρ·sin γ, which the force pins only through second-order effects, "
                  "follows something the model lacks (flank wear, for one); the σ of ρ and γ "
                  "given are at least their drift; read the radii",
                  spread.value("rho_drift_um", 0.0), spread.value("gamma_drift_deg", 0.0),
                  spread.value("windows", 0), spread.value("radius_drift_um", 0.0));
    warn("runout drifts", text.data());
  }
  json warnings = json::array();
  for (const std::vector<Warning>* list :
       std::array<const std::vector<Warning>*, 3>{&warnings_, &derived_, &notes_}) {
    for (const auto& w : *list) {
      warnings.push_back({{"kind", w.kind},
                          {"occurrences", w.occurrences},
                          {"samples", w.samples},
                          {"first_utime", w.first_utime_us},
                          {"detail", w.detail}});
    }
  }
  json residual = {{"fx", number_or_null(residual_[0].rms())},
                   {"fy", number_or_null(residual_[1].rms())},
                   {"fz", number_or_null(residual_[2].rms())},
                   {"measured", number_or_null(measured_rms_.rms())}};
  const bool two_edges = flutes_ >= 2;
  // Over the revolutions since a relabelling's lock, if there was one: fewer than "revolutions".
  const json alpha = {{"mean", two_edges ? number_or_null(f.alpha.mean()) : json(nullptr)},
                      {"std", two_edges ? number_or_null(f.alpha.stddev()) : json(nullptr)},
                      {"revolutions", f.alpha.n}};
  // Each rate's samples at their own rate (a reload may have changed it: reconfigure()).
  const double duration_s =
      duration_before_s_ +
      static_cast<double>(samples - samples_at_rate_change_) / config_.sample_rate_hz;
  json out{{"samples", samples},
           {"duration_s", duration_s},
           {"sample_rate_hz", config_.sample_rate_hz},
           {"revolutions", valid_},
           {"revolutions_measured", revolutions_},
           {"revolutions_cutting", std::llround(status_.cutting_revolutions)},
           {"spindle_rpm", number_or_null(rpm)},
           {"spindle_rpm_std", number_or_null(rpm_.stddev())},
           {"spindle_rpm_source", rpm_source},
           {"spindle_rpm_commanded", config_.model.process.spindle_rpm},
           {"tooth_event", std::string(status_.event_kind)},
           {"flute_labelling",
            "flute 0 = CE1, the flute whose period holds the largest force (no "
            "once-per-revolution reference)"},
           {"alpha_deg", alpha},
           {"tooth_period_s", periods},
           {"tooth_period_s_std", periods_std},
           {"peak_force_N", peak},
           {"peak_force_N_std", peak_std},
           {"delta_fy_N", two_edges ? number_or_null(f.delta_fy.mean()) : json(nullptr)},
           {"delta_fy_N_std", two_edges ? number_or_null(f.delta_fy.stddev()) : json(nullptr)},
           {"residual_rms_N", residual},
           {"model",
            {{"alpha_deg", two_edges ? number_or_null(f.model_alpha.mean()) : json(nullptr)},
             {"delta_fy_N", two_edges ? number_or_null(f.model_delta_fy.mean()) : json(nullptr)},
             {"lockstep", config_.lockstep},
             {"builds", status_.model_builds},
             {"steady_state", model_steady_state(status_)},
             // Identified parameters the model in lockstep took, fits it did not take, and
             // fits accepted that a newer one (or the run's end) overtook before it could.
             {"identified_parameters_taken", status_.identifications_taken},
             {"identified_parameters_rejected", status_.identifications_rejected},
             {"identified_parameters_superseded", status_.identifications_superseded},
             {"material", config_.model.material.name}}},
           {"alerts", alerts_},
           {"dropped_samples", in.samples_dropped},
           {"warnings", warnings},
           {"counters",
            {{"samples_in", in.samples_in},
             {"samples_flagged", in.samples_flagged},
             {"nonfinite_samples", in.nonfinite_samples},
             {"saturated_samples", in.saturated_samples},
             {"gaps", in.gaps},
             {"out_of_order_blocks", in.out_of_order_blocks},
             {"blocks_rejected", in.blocks_rejected},
             {"idle_revolutions", status_.idle_revolutions},
             {"alert_held_revolutions", status_.alert_held_revolutions}}},
           {"force_frame", "force on the tool; x feed, y cross-feed, z towards the spindle"}};
  for (const char* key : {"runout", "coefficients", "fit"}) {
    out[key] = identification_.is_object() && identification_.contains(key) ? identification_[key]
                                                                            : json(nullptr);
  }
  return out;
}

}  // namespace millwatch::monitor
