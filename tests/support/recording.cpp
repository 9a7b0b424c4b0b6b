#include "tests/support/recording.hpp"

#include <cmath>

#include "core/model/model_config.hpp"

namespace millwatch::test {

int Collector::count(monitor::PipelineEventKind kind) const {
  int n = 0;
  for (const auto& e : events) {
    n += e.kind == kind ? 1 : 0;
  }
  return n;
}

const monitor::PipelineEvent* Collector::first(monitor::PipelineEventKind kind) const {
  for (const auto& e : events) {
    if (e.kind == kind) {
      return &e;
    }
  }
  return nullptr;
}

Recording record(const sim::Scenario& s) {
  sim::CutSimulator sim(s);
  Recording r;
  r.sample_rate_hz = s.sample_rate_hz;
  const auto n = static_cast<std::size_t>(sim.total_samples());
  r.t.resize(n);
  r.fx.resize(n);
  r.fy.resize(n);
  r.fz.resize(n);
  sim.next_block(r.t, r.fx, r.fy, r.fz);
  r.truth = sim.truth();
  r.played = sim.played_steady_states();
  r.duration_s = static_cast<double>(n) / s.sample_rate_hz;
  return r;
}

Recording knocked_record(const sim::Scenario& s, double knocked, double from) {
  Recording r = record(s);
  const double per_rev = s.sample_rate_hz * 60.0 / s.spindle.actual_rpm;
  const auto half_turn = static_cast<std::size_t>(std::lround(0.5 * per_rev));
  const auto first = static_cast<std::size_t>(from * per_rev);
  const auto swapped = static_cast<std::size_t>((from + knocked) * per_rev);
  for (std::size_t i = first; i < swapped; ++i) {
    r.fx[i] = r.fx[i + half_turn];
    r.fy[i] = r.fy[i + half_turn];
    r.fz[i] = r.fz[i + half_turn];
  }
  return r;
}

void replay(monitor::Pipeline& p, const Recording& r, std::size_t block,
            const std::function<bool(std::int64_t, monitor::SampleBlock&)>& tamper, bool finish) {
  for (std::size_t i = 0, seq = 0; i < r.t.size(); i += block, ++seq) {
    const std::size_t n = std::min(block, r.t.size() - i);
    monitor::SampleBlock b{std::llround(r.t[i] * 1e6),
                           static_cast<std::int64_t>(seq),
                           r.sample_rate_hz,
                           std::span(r.fx).subspan(i, n),
                           std::span(r.fy).subspan(i, n),
                           std::span(r.fz).subspan(i, n)};
    if (tamper && !tamper(static_cast<std::int64_t>(seq), b)) {
      continue;  // the block is lost
    }
    p.process(b);
  }
  if (finish) {
    p.finish();
  }
}

void as_measured(sim::Scenario& s) {
  s.spindle.actual_rpm = 0.99 * s.model.process.spindle_rpm;
  s.noise.enabled = true;
  s.noise.sigma_N = {0.015, 0.015, 0.015};
  s.quantisation.enabled = true;
  s.quantisation.bits = 16;
  s.quantisation.range_N = {327.68, 327.68, 327.68};
}

sim::Scenario three_flute_cut_with_runout(double duration_s) {
  sim::Scenario s;
  s.sample_rate_hz = 50000.0;
  s.duration_s = duration_s;
  s.seed = 3;
  auto& m = s.model;
  m = model::without_effects(m);
  m.material.law = model::ForceLawKind::kLinearEdge;
  m.tool.flutes = 3;
  m.tool.diameter_mm = 0.6;
  m.process.operation = model::Operation::kSlot;
  m.process.radial_depth_mm = 0.6;
  m.process.feed_per_tooth_um = 3.0;
  m.process.axial_depth_mm = 0.05;
  model::set_effect(m, "runout", true);
  m.effects.runout.offset_um = 1.2;
  m.effects.runout.angle_rad = 0.5;
  m.resolution.steps_per_rev = 2880;
  as_measured(s);
  return s;
}

monitor::MonitorConfig monitor_for(const sim::Scenario& s) {
  monitor::MonitorConfig c;
  c.model = s.model;
  c.sample_rate_hz = s.sample_rate_hz;
  return c;
}

const sim::RevolutionTruth* truth_at(const Recording& r, double time_s) {
  const sim::RevolutionTruth* best = nullptr;
  for (const auto& t : r.truth) {
    if (best == nullptr || std::fabs(t.start_s - time_s) < std::fabs(best->start_s - time_s)) {
      best = &t;
    }
  }
  if (best == nullptr || best->spindle_rpm <= 0.0) {
    return nullptr;
  }
  return std::fabs(best->start_s - time_s) < 15.0 / best->spindle_rpm ? best : nullptr;
}

int complete_cutting_revolutions(const Recording& r, double from_s) {
  int n = 0;
  for (std::size_t i = 0; i + 1 < r.truth.size(); ++i) {
    const double end_s = r.truth[i + 1].start_s;
    n += r.truth[i].cutting && r.truth[i + 1].cutting && r.truth[i].start_s >= from_s &&
                 end_s <= r.duration_s
             ? 1
             : 0;
  }
  return n;
}

std::string warning_detail(const nlohmann::json& warnings, const std::string& kind) {
  for (const auto& w : warnings) {
    if (w["kind"] == kind) {
      return w["detail"].get<std::string>();
    }
  }
  return "";
}

}  // namespace millwatch::test
