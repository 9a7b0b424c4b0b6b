#pragma once
// Simulated recordings fed to a monitor pipeline, for the monitor's tests: a cut simulated
// with known truth, replayed in blocks (optionally tampered with), and a sink that collects
// what the pipeline emits.

#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/monitor/pipeline.hpp"
#include "core/sim/cut_simulator.hpp"

namespace millwatch::test {

/// Collects what a pipeline emits.
struct Collector : monitor::PipelineSink {
  std::vector<monitor::RevolutionRecord> revolutions;
  std::vector<monitor::SpindleUpdate> spindle;
  std::vector<monitor::Alert> alerts;
  std::vector<monitor::PipelineEvent> events;
  void on_revolution(const monitor::RevolutionRecord& r) override { revolutions.push_back(r); }
  void on_spindle(const monitor::SpindleUpdate& u) override { spindle.push_back(u); }
  void on_alert(const monitor::Alert& a) override { alerts.push_back(a); }
  void on_event(const monitor::PipelineEvent& e) override { events.push_back(e); }
  [[nodiscard]] int count(monitor::PipelineEventKind kind) const;
  /// The first event of a kind (nullptr: none).
  [[nodiscard]] const monitor::PipelineEvent* first(monitor::PipelineEventKind kind) const;
};

/// A recorded cut: the dynamometer's reading per sample, and the simulator's truth.
struct Recording {
  double sample_rate_hz = 0.0;
  std::vector<double> t, fx, fy, fz;
  std::vector<sim::RevolutionTruth> truth;  ///< one per revolution the simulator started
  sim::PlayedSteadyStates played;           ///< what the model's steady states played were like
  double duration_s = 0.0;
};

Recording record(const sim::Scenario& s);

/// The record of cut `s` with `knocked` revolutions from revolution `from` replaced by the
/// samples half a turn later (a knock: the same valleys, the flutes' forces swapped).
Recording knocked_record(const sim::Scenario& s, double knocked, double from);

/// Feeds a recording in blocks of `block` samples; `tamper` may change a block's samples or
/// timing first, or return false to lose the block. Calls finish() at the end unless told not.
void replay(monitor::Pipeline& p, const Recording& r, std::size_t block,
            const std::function<bool(std::int64_t, monitor::SampleBlock&)>& tamper = {},
            bool finish = true);

/// What a measurement chain adds to a simulated cut: the spindle 1 % below the commanded speed,
/// 0.015 N of noise per axis, a 16-bit converter over ±327.68 N.
void as_measured(sim::Scenario& s);

/// A 3-flute slot (linear-edge law, 0.6 mm tool, 3 µm/tooth) with 1.2 µm of runout at 50 kHz,
/// simulated as a real cut would differ from the model: noise and quantisation, a finer angle
/// grid (0.125°), the actual speed 1 % below the commanded one.
sim::Scenario three_flute_cut_with_runout(double duration_s = 0.5);

/// The monitor configuration of a simulated cut: its true model (commanded speed) and rate.
monitor::MonitorConfig monitor_for(const sim::Scenario& s);

/// The truth revolution whose start is nearest `time_s` (nullptr: none within a quarter
/// revolution). Truth revolutions start at the spindle's angle zero, not at a tooth event:
/// compare by index through revolution_index().
const sim::RevolutionTruth* truth_at(const Recording& r, double time_s);

/// Complete revolutions of the truth that cut, from `from_s` to the end of the record.
int complete_cutting_revolutions(const Recording& r, double from_s = 0.0);

/// The detail of the first warning of `kind` in a run summary's "warnings" ("" if there is none).
std::string warning_detail(const nlohmann::json& warnings, const std::string& kind);

}  // namespace millwatch::test
