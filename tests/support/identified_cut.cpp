#include "tests/support/identified_cut.hpp"

#include <chrono>
#include <cmath>
#include <complex>
#include <span>

#include "core/monitor/pipeline.hpp"

namespace millwatch::test {
namespace {

/// Keeps every revolution and fits each window as it is reported.
class FittingSink : public monitor::PipelineSink {
 public:
  FittingSink(IdentifiedCut& out, identify::WindowFitter& fitter) : out_(out), fitter_(fitter) {}

  void on_revolution(const monitor::RevolutionRecord& r) override {
    out_.order.push_back({static_cast<std::int64_t>(out_.revolutions.size()), -1});
    out_.revolutions.push_back(r);
    if (r.measured.bounded && r.spindle_rpm > 0.0) {
      rpm_sum_ += r.spindle_rpm;
      ++rpm_count_;
    }
  }
  void on_sync_average(const monitor::SyncAverage& s, const monitor::Lockstep*,
                       std::int64_t revolution, std::int64_t utime_us) override {
    if (rpm_count_ == 0 || s.revolutions() == 0) {
      return;
    }
    for (int a = 0; a < 3; ++a) {
      s.average(a, window_.force_N[static_cast<std::size_t>(a)]);
    }
    window_.spindle_rpm = rpm_sum_ / rpm_count_;
    window_.revolutions = s.revolutions();
    rpm_sum_ = 0.0;
    rpm_count_ = 0;
    identify::IdentifiedWindow w;
    const auto start = std::chrono::steady_clock::now();
    const identify::FitResult* previous = nullptr;
    for (auto it = out_.windows.rbegin(); it != out_.windows.rend(); ++it) {
      if (it->fit.ok) {
        previous = &it->fit;
        break;
      }
    }
    w.fit = fitter_.fit(window_, previous);
    w.fit_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    w.revolution = revolution;  // the window's last revolution
    w.utime_us = utime_us;
    w.window_revolutions = s.revolutions();
    out_.fit_seconds += w.fit_seconds;
    out_.order.push_back({-1, static_cast<int>(out_.windows.size())});
    out_.windows.push_back(std::move(w));
  }
  void on_alert(const monitor::Alert& a) override { out_.pipeline_alerts.push_back(a); }

 private:
  IdentifiedCut& out_;
  identify::WindowFitter& fitter_;
  identify::MeasuredRevolution window_;
  double rpm_sum_ = 0.0;
  int rpm_count_ = 0;
};

}  // namespace

IdentifiedCut identify_cut(const sim::Scenario& s, const monitor::MonitorConfig& c,
                           const identify::FitOptions& options) {
  IdentifiedCut out;
  sim::CutSimulator simulator(s);
  // The pipeline is built first for its filter, then the fitter and the sink that uses it.
  struct Forward : monitor::PipelineSink {
    monitor::PipelineSink* to = nullptr;
    void on_revolution(const monitor::RevolutionRecord& r) override { to->on_revolution(r); }
    void on_sync_average(const monitor::SyncAverage& a, const monitor::Lockstep* l,
                         std::int64_t rev, std::int64_t t) override {
      to->on_sync_average(a, l, rev, t);
    }
    void on_alert(const monitor::Alert& a) override { to->on_alert(a); }
  } forward;
  monitor::Pipeline pipeline(c, forward);
  const signal::ButterworthDesign filter = pipeline.filter();
  const bool zero_phase = c.filter_zero_phase;
  identify::WindowFitter fit(
      c.model,
      [filter, zero_phase](double hz) {
        const std::complex<double> h = filter.response(hz);
        return zero_phase ? std::complex<double>(std::norm(h), 0.0) : h;
      },
      options);
  FittingSink sink(out, fit);
  forward.to = &sink;

  const auto block = static_cast<std::size_t>(s.sample_rate_hz / 1000.0);
  std::vector<double> t(block), fx(block), fy(block), fz(block);
  for (std::int64_t seq = 0;; ++seq) {
    const std::size_t n = simulator.next_block(t, fx, fy, fz);
    if (n == 0) {
      break;
    }
    pipeline.process({std::llround(t[0] * 1e6), seq, s.sample_rate_hz, std::span(fx).first(n),
                      std::span(fy).first(n), std::span(fz).first(n)});
  }
  pipeline.finish();
  out.truth = simulator.truth();
  return out;
}

std::vector<monitor::Alert> replay_alerts(const IdentifiedCut& cut, monitor::AlertEngine& engine,
                                          bool with_estimates) {
  std::vector<monitor::Alert> alerts;
  auto keep = [&](const monitor::Alert& a) { alerts.push_back(a); };
  for (const IdentifiedCut::Step& step : cut.order) {
    if (step.window < 0) {
      engine.on_revolution(cut.revolutions[static_cast<std::size_t>(step.revolution)], keep);
    } else if (with_estimates) {
      engine.on_identification(cut.windows[static_cast<std::size_t>(step.window)], keep);
    }
  }
  return alerts;
}

}  // namespace millwatch::test
