// The continuous identifier: windows fitted in its worker thread, each result handed to the
// callback and handed over at its due revolution — waited for in a replay, taken when ready
// live (late ones counted, a backlog dropped oldest first; with a CPU budget, a rest after each
// fit, the windows skipped counted); a finished identifier ignores later windows.

#include "core/identify/identifier.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <complex>
#include <mutex>
#include <thread>
#include <vector>

#include "core/model/flute_positions.hpp"
#include "core/model/steady_state.hpp"

namespace millwatch::identify {
namespace {

model::ModelConfig three_flute_slot(double rho_um, double gamma_rad) {
  model::ModelConfig m = model::without_effects(model::ModelConfig{});
  m.material.law = model::ForceLawKind::kLinearEdge;
  m.tool.flutes = 3;
  m.tool.diameter_mm = 0.5;
  m.process.operation = model::Operation::kSlot;
  m.process.radial_depth_mm = 0.5;
  m.process.feed_per_tooth_um = 3.0;
  m.process.axial_depth_mm = 0.05;
  model::set_effect(m, "runout", true);
  m.effects.runout.offset_um = rho_um;
  m.effects.runout.angle_rad = gamma_rad;
  return m;
}

/// The exact revolution of a finer model (1440 steps against the fitter's 720).
MeasuredRevolution window_of(const model::ModelConfig& truth) {
  model::SteadyStateWorkspace ws;
  const auto& ss = model::evaluate_steady_state(truth, truth.process.spindle_rpm, 1440, ws);
  MeasuredRevolution m;
  m.force_N = {ss.mean.fx_N, ss.mean.fy_N, ss.mean.fz_N};
  m.spindle_rpm = truth.process.spindle_rpm;
  m.revolutions = 30;
  m.shared_bins = false;
  return m;
}

std::complex<double> pass_band(double hz) {
  return {hz < 3300.0 ? 1.0 : 0.0, 0.0};
}

TEST(Identifier, LiveItFitsWhatItGetsToDropsTheBacklogAndCountsLateResults) {
  const model::ModelConfig truth = three_flute_slot(1.2, 0.4);
  model::ModelConfig start = truth;
  start.effects.runout.offset_um = 0.0;
  std::atomic<int> calls{0};
  Identifier id(
      start, pass_band, FitOptions{}, [&](const IdentifiedWindow&) { ++calls; },
      HandOver::kWhenReady);
  const MeasuredRevolution w = window_of(truth);
  id.submit(w, 30, 1000, 60);
  // Due at once, but a fit takes tens of milliseconds: not waited for, counted late once.
  EXPECT_FALSE(id.take_due(60).has_value());
  EXPECT_FALSE(id.take_due(61).has_value());
  EXPECT_EQ(id.late(), 1);
  for (int k = 2; k <= 6; ++k) {
    id.submit(w, 30 * k, 1000 * k, 30 * k + 30);  // far faster than the worker fits
  }
  id.finish();
  id.submit(w, 999, 999, 999);  // after finish(): ignored
  // One fitting and at most two waiting at any time: at least three of six dropped.
  EXPECT_EQ(id.fitted() + id.superseded(), 6);
  EXPECT_GE(id.superseded(), 3);
  EXPECT_EQ(calls.load(), id.fitted());
  // Every result fitted is handed over, oldest first, the newest last.
  std::int64_t previous = 0;
  int handed = 0;
  while (const auto r = id.take_due(1000)) {
    EXPECT_GT(r->revolution, previous);
    previous = r->revolution;
    ++handed;
  }
  EXPECT_EQ(handed, id.fitted());
  EXPECT_EQ(previous, 180);
  const auto last = id.latest();
  ASSERT_TRUE(last.has_value());
  EXPECT_EQ(last->revolution, 180);  // the newest window is never dropped
  ASSERT_TRUE(last->fit.ok) << last->fit.message;
  EXPECT_NEAR(last->fit.rho_um.value, 1.2, 2.0 * last->fit.rho_um.sigma);
  EXPECT_LT(last->fit.rho_um.sigma, 0.05);
  EXPECT_GT(last->fit_seconds, 0.0);
}

TEST(Identifier, InAReplayEveryResultIsHandedOverAtItsDueRevolutionInOrder) {
  const model::ModelConfig truth = three_flute_slot(1.2, 0.4);
  model::ModelConfig start = truth;
  start.effects.runout.offset_um = 0.0;
  Identifier id(start, pass_band, FitOptions{}, nullptr, HandOver::kWait);
  const MeasuredRevolution w = window_of(truth);
  for (int k = 1; k <= 3; ++k) {
    id.submit(w, 30 * k, 1000 * k, 30 * k + 45);
  }
  EXPECT_FALSE(id.take_due(74).has_value());  // nothing due yet: no waiting either
  for (int k = 1; k <= 3; ++k) {
    const auto r = id.take_due(30 * k + 45);  // waits for the fit
    ASSERT_TRUE(r.has_value());
    EXPECT_EQ(r->revolution, 30 * k);
    ASSERT_TRUE(r->fit.ok) << r->fit.message;
    EXPECT_NEAR(r->fit.rho_um.value, 1.2, std::max(0.05, 2.0 * r->fit.rho_um.sigma));
  }
  EXPECT_FALSE(id.take_due(1000).has_value());
  EXPECT_EQ(id.fitted(), 3);
  EXPECT_EQ(id.superseded(), 0);
  EXPECT_EQ(id.late(), 0);
}

TEST(Identifier, ARunoutStepIsFoundInTheNextWindow) {
  const model::ModelConfig before = three_flute_slot(0.8, 0.4);
  const model::ModelConfig after = three_flute_slot(2.0, -1.0);
  model::ModelConfig start = before;
  start.effects.runout.offset_um = 0.0;
  Identifier id(start, pass_band, FitOptions{}, nullptr);
  id.submit(window_of(before), 30, 1, 60);
  while (id.fitted() < 1) {
    std::this_thread::yield();
  }
  const double rho_before = id.latest()->fit.rho_um.value;
  id.submit(window_of(after), 60, 2, 90);  // seeded with the old runout: must search afresh
  id.finish();
  const auto last = id.latest();
  ASSERT_TRUE(last.has_value() && last->fit.ok);
  EXPECT_NEAR(rho_before, 0.8, 0.05);
  EXPECT_NEAR(last->fit.rho_um.value, 2.0, std::max(0.05, 2.0 * last->fit.rho_um.sigma));
}

// Live with a CPU budget of 0.25: after each fit of t s of CPU the worker takes no window for
// 3t s of wall time. Windows submitted every 2 ms until three fits are done: every window is
// fitted or skipped for the budget (none superseded, none lost), and no fit starts before the
// previous one's rest is over — checked on the times the worker measured, not on a stopwatch.
TEST(Identifier, LiveWithACpuBudgetItRestsAfterEachFitAndCountsTheWindowsItSkips) {
  const model::ModelConfig truth = three_flute_slot(1.2, 0.4);
  model::ModelConfig start = truth;
  start.effects.runout.offset_um = 0.0;
  constexpr double kBudget = 0.25;
  std::mutex m;
  std::vector<IdentifiedWindow> results;
  Identifier id(
      start, pass_band, FitOptions{},
      [&](const IdentifiedWindow& w) {
        const std::lock_guard lock(m);
        results.push_back(w);
      },
      HandOver::kWhenReady, kBudget);
  EXPECT_EQ(id.budget_period_s(), 0.0);  // no fit yet
  const MeasuredRevolution w = window_of(truth);
  int submitted = 0;
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (id.fitted() < 3 && std::chrono::steady_clock::now() < give_up) {
    ++submitted;
    id.submit(w, 30 * submitted, 1000 * submitted, 30 * submitted + 30);
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  id.finish();
  ASSERT_GE(id.fitted(), 3);
  EXPECT_EQ(id.fitted() + id.skipped_for_budget(), submitted);
  EXPECT_EQ(id.superseded(), 0);
  EXPECT_GT(id.skipped_for_budget(), 0);
  const std::lock_guard lock(m);
  ASSERT_EQ(static_cast<std::int64_t>(results.size()), id.fitted());
  for (std::size_t i = 0; i < results.size(); ++i) {
    const IdentifiedWindow& r = results[i];
    ASSERT_TRUE(r.fit.ok) << r.fit.message;
    EXPECT_NEAR(r.fit.rho_um.value, 1.2, std::max(0.05, 2.0 * r.fit.rho_um.sigma));
    EXPECT_GT(r.fit_cpu_seconds, 0.0);
    if (i == 0) {
      EXPECT_EQ(r.revolution, 30);  // the first window is fitted at once
      continue;
    }
    const IdentifiedWindow& p = results[i - 1];
    const double rest_over_s =
        p.fit_started_s + p.fit_seconds + p.fit_cpu_seconds * (1.0 / kBudget - 1.0);
    EXPECT_GE(r.fit_started_s, rest_over_s - 1e-9) << "fit " << i;
    EXPECT_GT(r.revolution, p.revolution);
  }
  EXPECT_NEAR(id.budget_period_s(), results.back().fit_cpu_seconds / kBudget, 1e-12);
}

// A replay waits for every fit: the budget does not apply, every window is fitted.
TEST(Identifier, InAReplayTheBudgetIsIgnored) {
  const model::ModelConfig truth = three_flute_slot(1.2, 0.4);
  Identifier id(truth, pass_band, FitOptions{}, nullptr, HandOver::kWait, 0.001);
  const MeasuredRevolution w = window_of(truth);
  for (int k = 1; k <= 4; ++k) {
    id.submit(w, 30 * k, 1000 * k, 30 * k + 30);
  }
  for (int k = 1; k <= 4; ++k) {
    const auto r = id.take_due(30 * k + 30);
    ASSERT_TRUE(r.has_value()) << k;
    EXPECT_EQ(r->revolution, 30 * k);
  }
  id.finish();
  EXPECT_EQ(id.fitted(), 4);
  EXPECT_EQ(id.skipped_for_budget(), 0);
  EXPECT_EQ(id.superseded(), 0);
  EXPECT_EQ(id.budget_period_s(), 0.0);  // nothing for the alerts to wait on
}

TEST(Identifier, RefusesABudgetOutsideZeroToOne) {
  const model::ModelConfig m = three_flute_slot(1.2, 0.4);
  EXPECT_THROW(Identifier(m, pass_band, FitOptions{}, nullptr, HandOver::kWhenReady, 0.0),
               std::invalid_argument);
  Identifier id(m, pass_band, FitOptions{}, nullptr, HandOver::kWhenReady, 0.5);
  EXPECT_THROW(id.set_cpu_budget(2.0), std::invalid_argument);
}

}  // namespace
}  // namespace millwatch::identify
