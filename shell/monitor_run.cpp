#include "shell/monitor_run.hpp"

#include <algorithm>
#include <complex>
#include <numbers>
#include <utility>

#include "core/identify/fit_json.hpp"
#include "msgs/lcm_convert.hpp"

namespace millwatch::shell {
namespace {

/// Adds a pipeline's counts (before it is replaced) to `total`.
void carry(monitor::PipelineStatus& total, const monitor::PipelineStatus& s) {
  auto& t = total.input;
  const auto& c = s.input;
  t.samples_in += c.samples_in;
  t.samples_accepted += c.samples_accepted;
  t.samples_dropped += c.samples_dropped;
  t.samples_flagged += c.samples_flagged;
  t.nonfinite_samples += c.nonfinite_samples;
  t.saturated_samples += c.saturated_samples;
  t.gaps += c.gaps;
  t.out_of_order_blocks += c.out_of_order_blocks;
  t.blocks_rejected += c.blocks_rejected;
  total.identifications_taken += s.identifications_taken;
  total.identifications_rejected += s.identifications_rejected;
  total.identifications_superseded += s.identifications_superseded;
  total.revolutions += s.revolutions;
  total.valid_revolutions += s.valid_revolutions;
  total.idle_revolutions += s.idle_revolutions;
  total.alert_held_revolutions += s.alert_held_revolutions;
  total.flutes_relabelled += s.flutes_relabelled;
  total.relabelled_from_revolution =
      std::max(total.relabelled_from_revolution, s.relabelled_from_revolution);
  total.model_builds += s.model_builds;
  total.model_builds_unsettled += s.model_builds_unsettled;
  if (s.model_unsettled_slots_most > total.model_unsettled_slots_most) {
    total.model_unsettled_slots_most = s.model_unsettled_slots_most;
    total.model_slots_of_most = s.model_slots_of_most;
  }
  total.model_builds_area_unsettled += s.model_builds_area_unsettled;
  total.cutting_revolutions += s.cutting_revolutions;
}

/// Why identification does not run (empty: it runs).
std::string identification_off(bool requested, const monitor::MonitorConfig& c) {
  if (!requested) {
    return "--no-identify";
  }
  return c.identification.enabled ? "" : "identification.enabled is false";
}

identify::FitOptions fit_options(const monitor::MonitorConfig& c) {
  identify::FitOptions o;
  o.extra_parameters = c.identification.extra_parameters;
  o.runout_prior_um = c.identification.runout_prior_um;
  return o;
}

}  // namespace

MonitorRun::MonitorRun(const monitor::MonitorConfig& config, Options options)
    : options_(std::move(options)),
      summary_(config),
      shell_sink_(summary_, options_.source_name),
      last_status_wall_(std::chrono::steady_clock::now()) {
  shell_sink_.set_observer(options_.observer);
  if (options_.lcm != nullptr) {
    output_ =
        std::make_unique<messaging::LcmOutput>(*options_.lcm, options_.channels, &shell_sink_);
  }
  pipeline_ = std::make_unique<monitor::Pipeline>(config, sink());
  std::string off = identification_off(options_.identify, config);
  if (off.empty()) {
    start_identifier(config);
  }
  summary_.set_identification_off(std::move(off));
}

void MonitorRun::start_identifier(const monitor::MonitorConfig& config) {
  const signal::ButterworthDesign filter = pipeline_->filter();
  identify::FilterResponse response = [filter, zero_phase = config.filter_zero_phase](double hz) {
    // Zero phase: the filter forwards and backwards, |H|² without delay.
    const std::complex<double> h = filter.response(hz);
    return zero_phase ? std::complex<double>(std::norm(h), 0.0) : h;
  };
  if (identifier_) {
    identifier_->restart(config.model, std::move(response),
                         fit_options(config));  // does not wait for a fit
    identifier_->set_cpu_budget(config.identification.cpu_budget);
  } else {
    identifier_ = std::make_unique<identify::Identifier>(
        config.model, std::move(response), fit_options(config),
        [this](const identify::IdentifiedWindow& w) { on_identified(w); }, options_.hand_over,
        config.identification.cpu_budget);  // live only: a replay waits for every fit
  }
  pipeline_->attach_identifier(identifier_.get());
}

MonitorRun::~MonitorRun() {
  if (identifier_) {
    pipeline_->attach_identifier(nullptr);
    identifier_->finish();
  }
}

void MonitorRun::on_identified(const identify::IdentifiedWindow& w) {
  {
    const std::lock_guard lock(scatter_mutex_);
    scatter_.add(w.fit);
  }
  if (options_.lcm != nullptr) {
    const std::lock_guard lock(publish_mutex_);
    const runout_estimate_t runout = messaging::runout_estimate(w);
    const force_coefficients_t coefficients = messaging::force_coefficients(w);
    // Counted with the publisher thread's messages: the status's messages_published and
    // messages_dropped cover every output.
    const int runout_result = options_.lcm->publish(options_.channels.runout, &runout);
    const int coefficients_result =
        options_.lcm->publish(options_.channels.coefficients, &coefficients);
    output_->count_published_elsewhere(runout_result == 0);
    output_->count_published_elsewhere(coefficients_result == 0);
  }
}

monitor::PipelineSink& MonitorRun::sink() {
  if (output_) {
    return *output_;
  }
  return shell_sink_;
}

bool MonitorRun::process(const monitor::SampleBlock& block) {
  const bool accepted = pipeline_->process(block);
  if (status_due_ || block.utime_us >= next_status_utime_us_) {
    publish_status();
    status_due_ = false;
    next_status_utime_us_ =
        block.utime_us + static_cast<std::int64_t>(options_.status_period_s * 1e6);
  }
  return accepted;
}

void MonitorRun::idle() {
  if (std::chrono::steady_clock::now() - last_status_wall_ >
      std::chrono::duration<double>(options_.status_period_s)) {
    publish_status();
  }
}

std::unique_ptr<monitor::Pipeline> MonitorRun::replace_pipeline(
    std::unique_ptr<monitor::Pipeline> next) {
  // Samples held for zero-phase filtering are measured first; its alerts are cleared (the new
  // pipeline starts with none raised and raises again what still holds).
  pipeline_->hand_over("configuration reloaded");
  const monitor::PipelineStatus last = pipeline_->status();
  carry(carried_, last);
  carried_utime_us_ = std::max(carried_utime_us_, last.utime_us);
  std::unique_ptr<monitor::Pipeline> old = std::exchange(pipeline_, std::move(next));
  pipeline_->continue_numbering(carried_.revolutions, old->last_spindle_seq(), carried_utime_us_);
  // A gap across the reload is counted (at the same rate).
  pipeline_->continue_input_after(*old);
  summary_.reconfigure(pipeline_->config(), carried_.revolutions, carried_utime_us_,
                       carried_.input.samples_accepted);
  old->attach_identifier(nullptr);
  std::string off = identification_off(options_.identify, pipeline_->config());
  if (off.empty()) {
    start_identifier(pipeline_->config());  // the new configuration's model
  }  // else the identifier stays idle: no pipeline hands it windows
  summary_.set_identification_off(std::move(off));
  return old;
}

monitor::PipelineStatus MonitorRun::status() const {
  monitor::PipelineStatus s = pipeline_->status();
  if (s.input.samples_accepted == 0) {
    s.utime_us = carried_utime_us_;  // a pipeline that has taken no sample yet has no time
  }
  carry(s, carried_);
  if (options_.source_losses) {
    options_.source_losses(s);
  }
  return s;
}

void MonitorRun::publish_status() {
  if (output_) {
    output_->publish_status(status());
  }
  last_status_wall_ = std::chrono::steady_clock::now();
}

void MonitorRun::finish() {
  pipeline_->finish();
  const monitor::PipelineStatus final_status = status();
  if (output_) {
    output_->publish_status(final_status);
  }
  summary_.finish(final_status);
  if (identifier_) {
    pipeline_->attach_identifier(nullptr);
    identifier_->finish();  // the window in progress and any waiting are fitted
    if (const auto last = identifier_->latest()) {
      // The last window's estimates, with σ's no smaller than the windows' scatter: a window
      // can state a small σ by chance where the force pins the runout poorly.
      identify::WindowScatter::Widening how;
      identify::WindowScatter::Scatter spread;
      identify::IdentifiedWindow window = *last;
      {
        const std::lock_guard lock(scatter_mutex_);
        window.fit = scatter_.widened(last->fit, how);
        spread = scatter_.scatter();
      }
      nlohmann::json j = identify::to_json(window);
      constexpr double kDeg = 180.0 / std::numbers::pi;
      // Too few windows state no scatter (null, not 0: "no scatter" would read as "steady").
      using Scatter = identify::WindowScatter;
      const bool scatters = spread.windows >= Scatter::kLeastWindows;
      const bool drifts = spread.windows >= Scatter::kLeastDriftWindows;
      const auto known = [](bool k, const nlohmann::json& v) { return k ? v : nlohmann::json(); };
      j["fit"]["window_scatter"] = {
          {"windows", spread.windows},
          {"rho_std_um", known(scatters, spread.rho_um)},
          {"gamma_std_deg", known(scatters, spread.gamma_rad * kDeg)},
          {"r_minus_r_ce1_std_um", known(scatters, spread.radius_from_ce1_um)},
          {"widened", how.by_scatter},
          {"rho_drift_um", known(drifts, spread.rho_drift_um)},
          {"gamma_drift_deg", known(drifts, spread.gamma_drift_rad * kDeg)},
          {"radius_drift_um", known(drifts, spread.radius_drift_um)},
          {"widened_by_drift", how.by_drift}};
      j["fit"]["windows_fitted"] = identifier_->fitted();
      j["fit"]["windows_dropped"] = identifier_->superseded();  // live, behind the windows
      j["fit"]["results_late"] = identifier_->late();           // live, taken after they were due
      j["fit"]["windows_skipped_for_budget"] =
          identifier_->skipped_for_budget();  // live, on purpose
      summary_.set_identification(j);
    }
  }
}

void MonitorRun::drain() {
  if (output_) {
    output_->drain();
  }
}

}  // namespace millwatch::shell
