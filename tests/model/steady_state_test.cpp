#include "core/model/steady_state.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cfenv>
#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "core/config/json_reader.hpp"
#include "core/model/force_law.hpp"
#include "core/model/milling_model.hpp"
#include "core/model/nearest_removal.hpp"
#include "core/model/periodic_response.hpp"
#include "core/signal/butterworth_lowpass.hpp"
#include "tests/support/allocation_counter.hpp"
#include "tests/support/helix_integral.hpp"

namespace millwatch::model {
namespace {

// The rigid chip's nearest removal against its definition, one sweep from the nearest pass back
// to the oldest keeping the first of equal sums and skipping passes that removed nothing (the
// evaluator's loop before the lanes): the same sum and pass, bit for bit, for every look-back
// the evaluator uses (1–9 passes, the copper preset's 32, the most configurable, 64, and 65),
// with many ties (chips and deficits on a coarse grid), passes that removed nothing, a NaN.
TEST(NearestRemoval, IsTheOneSweepsMinimumAndItsNearestPass) {
  std::mt19937_64 rng(2007);
  std::uniform_int_distribution<int> grid(-4, 12);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int ties = 0, none = 0;
  for (const int passes : {1, 2, 3, 4, 5, 6, 7, 8, 9, 32, 64, 65}) {
    std::vector<double> g(static_cast<std::size_t>(passes));
    std::vector<double> deficit(g.size());
    for (int trial = 0; trial < 4000; ++trial) {
      const double removed_share = trial % 4 == 0 ? 0.0 : unit(rng);  // a quarter remove nothing
      for (std::size_t m = 0; m < g.size(); ++m) {
        g[m] = 0.25 * grid(rng);
        deficit[m] = unit(rng) < removed_share ? 0.125 * grid(rng) : kNoRemoval;
      }
      if (trial % 97 == 0) {
        deficit[g.size() / 2] = std::numeric_limits<double>::quiet_NaN();
      }
      double h = kNoRemoval;
      int at = 0;
      int equal = 0;
      for (int n = 1; n <= passes; ++n) {
        const double d = deficit[static_cast<std::size_t>(passes - n)];
        if (d == kNoRemoval) {
          continue;
        }
        const double c = g[static_cast<std::size_t>(passes - n)] + d;
        equal += c == h ? 1 : 0;
        if (c < h) {
          h = c;
          at = n;
          equal = 0;
        }
      }
      ties += equal > 0 ? 1 : 0;
      none += at == 0 ? 1 : 0;
      const auto [chip, back] = nearest_removal(g.data(), deficit.data(), passes);
      ASSERT_EQ(back, at) << passes << " passes, trial " << trial;
      ASSERT_TRUE(chip == h || (std::isinf(chip) && std::isinf(h))) << chip << " " << h;
    }
  }
  std::printf("%d draws with a tie at the minimum, %d with no removal\n", ties, none);
  EXPECT_GT(ties, 1000);
  EXPECT_GT(none, 1000);
}

constexpr double kPi = std::numbers::pi;

/// [000]'s cp-Ti case, with the ploughing normal coefficient lowered from Table 2's 79.64 to 70 so
/// that F_n rises at h_min: the deflection balance then has one root, and the time-marching
/// model's answer does not depend on its Newton start (see DeflectionTakesTheSmallestRoot).
ModelConfig reference_case(int steps = 360) {
  ModelConfig c;
  c.material.power_law.k_np_Nmm = 70.0;
  c.effects.dynamometer.enabled = false;
  c.effects.helix_lag.discs = 4;
  c.resolution.steps_per_rev = steps;
  return c;
}

double peak_of(const ForceWaveform& f) {
  double peak = 0.0;
  for (std::size_t k = 0; k < f.fx_N.size(); ++k) {
    peak = std::max({peak, std::fabs(f.fx_N[k]), std::fabs(f.fy_N[k]), std::fabs(f.fz_N[k])});
  }
  return peak;
}

double max_difference(const ForceWaveform& a, const ForceWaveform& b, std::size_t stride = 1) {
  double d = 0.0;
  for (std::size_t k = 0; k < a.fx_N.size(); ++k) {
    const std::size_t kb = k * stride;
    d = std::max({d, std::fabs(a.fx_N[k] - b.fx_N[kb]), std::fabs(a.fy_N[k] - b.fy_N[kb]),
                  std::fabs(a.fz_N[k] - b.fz_N[kb])});
  }
  return d;
}

/// The evaluator against the time-marching model run from reset() for many revolutions: every
/// chip (bottom disc, each flute, revolutions R..R+W) where MillingModel has settled (its chip
/// repeats after the slot's period), and, for an exact cycle, every force sample of the cycle
/// where MillingModel has settled (revolution R + m equals R + L + m).
struct Agreement {
  double chip_difference_um = 0.0;
  double force_difference_N = 0.0;
  double peak_N = 0.0;
  int chips_compared = 0, chips_unsettled = 0;
  int forces_compared = 0, forces_unsettled = 0;
  int cycle = 0;
  bool exact = false;
};

Agreement compare_with_time_marching(const ModelConfig& c, int warm_up = 300) {
  const int steps = c.resolution.steps_per_rev;
  const int flutes = c.tool.flutes;
  SteadyStateWorkspace ws(c, steps);
  const SteadyState& st = evaluate_steady_state(c, c.process.spindle_rpm, steps, ws);
  Agreement out;
  out.cycle = st.cycle_revolutions;
  out.exact = st.cycle_exact;
  const int cycle = st.cycle_revolutions;
  const int longest = st.stats.longest_slot_period_revolutions;
  MillingModel m(c);
  const int start = (warm_up + cycle - 1) / cycle * cycle;  // R ≡ 0 (mod L)
  for (int r = 0; r < start; ++r) {
    m.step_revolution();
  }
  const int window = std::max(2 * cycle, 2 * longest) + 2;
  std::vector<double> chips(static_cast<std::size_t>(window * flutes * steps));
  std::vector<double> forces(static_cast<std::size_t>(window * 3 * steps));
  for (int r = 0; r < window; ++r) {
    m.step_revolution();
    for (int k = 0; k < steps; ++k) {
      for (int j = 0; j < flutes; ++j) {
        chips[static_cast<std::size_t>((r * flutes + j) * steps + k)] = m.chip_um(j, k);
      }
      forces[static_cast<std::size_t>((r * 3 + 0) * steps + k)] = m.forces().fx_N[k];
      forces[static_cast<std::size_t>((r * 3 + 1) * steps + k)] = m.forces().fy_N[k];
      forces[static_cast<std::size_t>((r * 3 + 2) * steps + k)] = m.forces().fz_N[k];
    }
  }
  const int pitch_steps = steps / flutes;  // uniform pitch on the grid
  for (int r = 0; r + longest < window; ++r) {
    for (int j = 0; j < flutes; ++j) {
      for (int k = 0; k < steps; ++k) {
        const int b = ((k - j * pitch_steps) % steps + steps) % steps;
        const int p = ws.slot_period_revolutions(0, b);
        const double now = chips[static_cast<std::size_t>((r * flutes + j) * steps + k)];
        const double later = chips[static_cast<std::size_t>(((r + p) * flutes + j) * steps + k)];
        if (std::fabs(now - later) > 1e-10) {
          ++out.chips_unsettled;
          continue;
        }
        ++out.chips_compared;
        out.chip_difference_um =
            std::max(out.chip_difference_um, std::fabs(ws.chip_um(j, b, start + r) - now));
      }
    }
  }
  if (st.cycle_exact) {
    for (int r = 0; r < cycle; ++r) {
      for (int a = 0; a < 3; ++a) {
        const auto rev = st.revolution(r, a);
        for (int k = 0; k < steps; ++k) {
          const double now = forces[static_cast<std::size_t>((r * 3 + a) * steps + k)];
          const double later = forces[static_cast<std::size_t>(((r + cycle) * 3 + a) * steps + k)];
          out.peak_N = std::max(out.peak_N, std::fabs(now));
          if (std::fabs(now - later) > 1e-10) {
            ++out.forces_unsettled;
            continue;
          }
          ++out.forces_compared;
          out.force_difference_N =
              std::max(out.force_difference_N, std::fabs(rev[static_cast<std::size_t>(k)] - now));
        }
      }
    }
  }
  return out;
}

struct Combination {
  const char* name;
  std::vector<const char*> effects;  // switched on over without_effects(reference_case())
};

// The evaluator and the time-marching model are two implementations of the same physics: where
// MillingModel has settled (nearly everywhere after 300 revolutions; thin chips under
// deflection relax very slowly) they agree chip by chip and, for cycles short enough to compare,
// sample by sample over the whole cycle — to 1e-16 without deflection, and to MillingModel's
// deflection solve (it stops at |Δ ln h| < 1e-4, ~1e-8 relative) with it.
TEST(SteadyState, MatchesTheTimeMarchingModelForEveryEffectCombination) {
  const std::vector<Combination> combinations = {
      {"plain", {}},
      {"runout", {"runout"}},
      {"+trochoidal", {"runout", "trochoidal"}},
      {"+multi_pass", {"runout", "trochoidal", "multi_pass"}},
      {"+min_chip", {"runout", "trochoidal", "multi_pass", "min_chip"}},
      {"+helix_lag", {"runout", "trochoidal", "multi_pass", "min_chip", "helix_lag"}},
      {"+deflection",
       {"runout", "trochoidal", "multi_pass", "min_chip", "helix_lag", "deflection"}},
      {"+accumulation",
       {"runout", "trochoidal", "multi_pass", "min_chip", "helix_lag", "deflection",
        "accumulation"}},
      {"+flank_wear",
       {"runout", "trochoidal", "multi_pass", "min_chip", "helix_lag", "deflection", "accumulation",
        "flank_wear"}},
      {"deflection alone", {"deflection"}},
      {"accumulation alone", {"accumulation"}},
      {"min_chip and deflection", {"min_chip", "deflection"}},
      {"runout, helix and deflection", {"runout", "helix_lag", "deflection"}},
      {"runout and accumulation", {"runout", "multi_pass", "accumulation"}},
  };
  for (const auto& combination : combinations) {
    ModelConfig c = without_effects(reference_case());
    for (const char* e : combination.effects) {
      set_effect(c, e, true);
    }
    c.effects.flank_wear.wear_um = {6.0, 2.0};
    // Runout with helix: the rigid axis (per-disc geometry, the default) and [000]'s tip pattern.
    const bool both = c.effects.runout.enabled && c.effects.helix_lag.enabled;
    for (RunoutHelix helix : {RunoutHelix::kRigidAxis, RunoutHelix::kTipPattern}) {
      if (helix == RunoutHelix::kTipPattern && !both) {
        continue;
      }
      SCOPED_TRACE(std::string(combination.name) + ", " + to_string(helix));
      c.effects.runout.helix = helix;
      const Agreement a = compare_with_time_marching(c);
      EXPECT_GT(a.chips_compared, 20 * a.chips_unsettled);
      EXPECT_LT(a.chip_difference_um, 1e-7);
      if (a.exact && a.cycle <= 16) {
        EXPECT_GT(a.forces_compared, 20 * a.forces_unsettled);
        EXPECT_LT(a.force_difference_N, 1e-7 * std::max(1.0, a.peak_N));
      }
    }
  }
}

// The same for the other force laws, three flutes, side milling and a non-uniform pitch that
// falls on the grid, all with every effect of the reference case on.
TEST(SteadyState, MatchesTheTimeMarchingModelForEveryLawAndGeometry) {
  struct Case {
    const char* name;
    ModelConfig config;
  };
  std::vector<Case> cases;
  ModelConfig c = reference_case();
  c.material.law = ForceLawKind::kLinearEdge;
  cases.push_back({"linear edge", c});
  c = reference_case();
  c.material.law = ForceLawKind::kKronenberg;
  cases.push_back({"Kronenberg", c});
  c = reference_case();
  c.tool.flutes = 3;
  cases.push_back({"three flutes", c});
  c = reference_case();
  c.tool.flutes = 4;
  c.tool.pitch_deg = {80.0, 100.0, 80.0, 100.0};
  cases.push_back({"variable pitch on the grid", c});
  c = reference_case();
  c.process.operation = Operation::kUpMilling;
  c.process.radial_depth_mm = 0.1;
  cases.push_back({"up milling", c});
  c = reference_case();
  c.process.operation = Operation::kDownMilling;
  c.process.radial_depth_mm = 0.1;
  cases.push_back({"down milling", c});
  for (const auto& k : cases) {
    SCOPED_TRACE(k.name);
    const Agreement a = compare_with_time_marching(k.config);
    EXPECT_GT(a.chips_compared, 20 * a.chips_unsettled);
    if (k.config.tool.pitch_deg.empty()) {
      EXPECT_LT(a.chip_difference_um, 1e-7);
    }
    if (a.exact && a.cycle <= 16) {
      EXPECT_GT(a.forces_compared, 20 * a.forces_unsettled);
      EXPECT_LT(a.force_difference_N, 1e-7 * std::max(1.0, a.peak_N));
    }
  }
}

// Analytic case: circular path, no runout, one disc, linear shear + edge law. One flute is in the
// slot at a time with h = f_t·sin θ: F_t = (K_tc·h + K_te)·a_p, F_n = (K_nc·h + K_ne)·a_p,
// F_a = (K_ac·h + K_ae)·a_p, projected by [000] eq 7.
TEST(SteadyState, LinearLawSlotMatchesClosedForm) {
  ModelConfig c = without_effects(ModelConfig{});
  c.material.law = ForceLawKind::kLinearEdge;
  c.material.linear_edge.k_ac_N_per_mm2 = 200.0;
  c.material.linear_edge.k_ae_N_per_mm = 3.0;
  const int steps = 720;
  SteadyStateWorkspace ws(c, steps);
  const SteadyState& st = evaluate_steady_state(c, 25000.0, steps, ws);
  const auto& le = c.material.linear_edge;
  const double ap = c.process.axial_depth_mm;
  const double ft_mm = c.process.feed_per_tooth_um * 1e-3;
  int compared = 0;
  for (int k = 0; k < steps; ++k) {
    const double phi = 2.0 * kPi * k / steps;
    double fx = 0.0, fy = 0.0, fz = 0.0;
    bool at_an_edge = false;
    for (int j = 0; j < 2; ++j) {
      const double theta = std::fmod(phi - j * kPi + 4.0 * kPi, 2.0 * kPi);
      at_an_edge = at_an_edge || std::fabs(theta) < 1e-9 || std::fabs(theta - kPi) < 1e-9;
      if (theta > kPi) {
        continue;
      }
      const double h = ft_mm * std::sin(theta);
      const double ft = (le.k_tc_N_per_mm2 * h + le.k_te_N_per_mm) * ap;
      const double fn = (le.k_nc_N_per_mm2 * h + le.k_ne_N_per_mm) * ap;
      fx += -ft * std::cos(theta) - fn * std::sin(theta);
      fy += ft * std::sin(theta) - fn * std::cos(theta);
      fz += (le.k_ac_N_per_mm2 * h + le.k_ae_N_per_mm) * ap;
    }
    if (at_an_edge) {
      continue;  // entry and exit: whether h = f_t·sin θ is ±1e-16 decides the edge force
    }
    ++compared;
    const auto uk = static_cast<std::size_t>(k);
    ASSERT_NEAR(st.mean.fx_N[uk], fx, 1e-12) << k;
    ASSERT_NEAR(st.mean.fy_N[uk], fy, 1e-12) << k;
    ASSERT_NEAR(st.mean.fz_N[uk], fz, 1e-12) << k;
  }
  EXPECT_EQ(compared, steps - 2);
  EXPECT_EQ(st.cycle_revolutions, 1);
}

// Helix lag: the discs approximate the integral over the lag, uniform over [0, β] ([000] eqs
// 2-4, 6, 8); for the linear law it has a closed form, and the midpoint rule converges.
TEST(SteadyState, HelixDiscsConvergeToTheAnalyticIntegral) {
  ModelConfig c = without_effects(ModelConfig{});
  c.material.law = ForceLawKind::kLinearEdge;
  c.material.linear_edge.k_te_N_per_mm = 0.0;
  c.material.linear_edge.k_ne_N_per_mm = 0.0;
  c.effects.helix_lag.enabled = true;
  c.tool.helix_deg = 45.0;
  c.process.axial_depth_mm = 0.2;  // a large lag, β ≈ 57°
  double previous_error = 1e9;
  SteadyStateWorkspace ws;
  for (int discs : {5, 10, 20, 40}) {
    c.effects.helix_lag.discs = discs;
    const SteadyState& st = evaluate_steady_state(c, 25000.0, 720, ws);
    double error = 0.0;
    double scale = 0.0;
    for (int k = 0; k < 720; ++k) {
      const double exact = test::helix_integral_fx_N(c, 2.0 * kPi * k / 720);
      error = std::max(error, std::fabs(st.mean.fx_N[static_cast<std::size_t>(k)] - exact));
      scale = std::max(scale, std::fabs(exact));
    }
    EXPECT_LT(error, previous_error) << discs;
    if (discs == 40) {
      EXPECT_LT(error / scale, 2e-3);
    }
    previous_error = error;
  }
}

// No snapping: a pitch between two grid steps (180.25° at 0.5° steps) gives the force a much
// finer grid gives (where that pitch falls on the grid). Without pass memory each flute is
// evaluated on its own immersion grid (exact); with memory the flutes share the slots and the
// force is interpolated onto the grid — still well ahead of the nearest pitch on the grid. And
// the force moves continuously with the pitch.
TEST(SteadyState, PitchBetweenGridStepsIsNotSnapped) {
  ModelConfig memoryless = without_effects(ModelConfig{});
  for (const char* e : {"runout", "trochoidal", "multi_pass", "helix_lag"}) {
    set_effect(memoryless, e, true);
  }
  memoryless.effects.helix_lag.discs = 5;
  ModelConfig with_memory = reference_case(720);
  // Deflection: memory, one revolution; without min_chip's regime switch, a genuine jump.
  with_memory.effects.accumulation.enabled = false;
  with_memory.effects.min_chip.enabled = false;
  for (const ModelConfig& base : {memoryless, with_memory}) {
    const bool memory = base.effects.deflection.enabled;
    SCOPED_TRACE(memory ? "with memory" : "memoryless");
    ModelConfig c = base;
    c.tool.pitch_deg = {180.25, 179.75};
    SteadyStateWorkspace coarse_ws;
    SteadyStateWorkspace fine_ws;
    const ForceWaveform exact = evaluate_steady_state(c, 25000.0, 7200, fine_ws).mean;
    const ForceWaveform off_grid = evaluate_steady_state(c, 25000.0, 720, coarse_ws).mean;
    ModelConfig snapped = c;
    snapped.tool.pitch_deg = {180.5, 179.5};  // what snapping to the 0.5° grid gives
    const ForceWaveform on_grid = evaluate_steady_state(snapped, 25000.0, 720, coarse_ws).mean;
    ModelConfig uniform = c;
    uniform.tool.pitch_deg = {};
    const ForceWaveform uniform_coarse =
        evaluate_steady_state(uniform, 25000.0, 720, coarse_ws).mean;
    const ForceWaveform uniform_fine = evaluate_steady_state(uniform, 25000.0, 7200, fine_ws).mean;
    const double grid_error = max_difference(uniform_coarse, uniform_fine, 10);
    const double error = max_difference(off_grid, exact, 10);
    const double snapping_error = max_difference(on_grid, exact, 10);
    if (memory) {
      EXPECT_LT(error, 0.5 * snapping_error);
    } else {
      // no worse than the coarse grid is anyway with a pitch on it
      EXPECT_LT(error, 2.0 * grid_error + 1e-12);
      EXPECT_LT(error, 0.01 * snapping_error);
    }
    // Continuous: the force moves less and less as the pitch moves less (by a decade at least
    // 2× less: near the entry the power law's F ∝ h^0.53 is continuous but not Lipschitz).
    double previous_change = 0.0;
    for (double nudge : {0.1, 0.01, 0.001}) {
      ModelConfig nudged = c;
      nudged.tool.pitch_deg = {180.25 + nudge, 179.75 - nudge};
      const double change =
          max_difference(evaluate_steady_state(nudged, 25000.0, 720, coarse_ws).mean, off_grid);
      EXPECT_GT(change, 0.0) << nudge;
      if (previous_change > 0.0) {
        EXPECT_LT(change, 0.5 * previous_change) << nudge;
      }
      previous_change = change;
    }
  }
}

// Smooth in the runout: the force moves in proportion to a small change of ρ or γ (no steps
// from a grid), for the linear law whose force is continuous where a flute enters the cut.
TEST(SteadyState, ForceMovesInProportionToSmallRunoutChanges) {
  ModelConfig c = without_effects(reference_case(720));
  for (const char* e : {"runout", "trochoidal", "multi_pass", "helix_lag"}) {
    set_effect(c, e, true);
  }
  c.material.law = ForceLawKind::kLinearEdge;
  c.material.linear_edge.k_te_N_per_mm = 0.0;
  c.material.linear_edge.k_ne_N_per_mm = 0.0;
  SteadyStateWorkspace ws;
  const ForceWaveform base = evaluate_steady_state(c, 25000.0, 720, ws).mean;
  for (int which = 0; which < 2; ++which) {
    std::array<double, 2> change{};
    for (int s = 0; s < 2; ++s) {
      ModelConfig d = c;
      const double delta = s == 0 ? 1e-6 : 1e-5;
      (which == 0 ? d.effects.runout.offset_um : d.effects.runout.angle_rad) += delta;
      change[static_cast<std::size_t>(s)] =
          max_difference(evaluate_steady_state(d, 25000.0, 720, ws).mean, base);
    }
    EXPECT_GT(change[0], 0.0) << which;
    EXPECT_NEAR(change[1] / change[0], 10.0, 1.0) << which;
  }
}

/// Root-mean-square of the resultant (Fx, Fy) over a revolution, and of a difference.
double rms_xy(const ForceWaveform& a, const ForceWaveform* b = nullptr) {
  double sum = 0.0;
  for (std::size_t k = 0; k < a.fx_N.size(); ++k) {
    const double x = a.fx_N[k] - (b != nullptr ? b->fx_N[k] : 0.0);
    const double y = a.fy_N[k] - (b != nullptr ? b->fy_N[k] : 0.0);
    sum += x * x + y * y;
  }
  return std::sqrt(sum / static_cast<double>(a.fx_N.size()));
}

/// The evaluator's mean revolution and MillingModel's settled revolution of one configuration.
struct BothModels {
  ForceWaveform evaluator, marching;
};
BothModels both_models(const ModelConfig& c) {
  SteadyStateWorkspace ws;
  BothModels out;
  out.evaluator = evaluate_steady_state(c, c.process.spindle_rpm, c.resolution.steps_per_rev, ws,
                                        SteadyStateOutput::kMean)
                      .mean;
  MillingModel m(c);
  m.warm_up();
  out.marching = m.forces();
  return out;
}

// The rigid tool axis (RunoutHelix::kRigidAxis) gives disc i the runout angle
// γ + lag_i; it must reduce to [000]'s tip pattern wherever the two cannot differ:
//   helix lag off (one disc at the tip, lag 0): the same model, every effect on;
//   one disc with helix (lag_0 = β/2 at its midpoint): the tip pattern with γ + β/2;
//   no runout, or ρ = 0: nothing for the angle to act on;
//   one flute on the circular path: the chip f_t·sin θ + r_0 − r_0 has no radius term.
// Both the evaluator and MillingModel, to rounding.
TEST(SteadyState, RigidAxisRunoutReducesToTheTipPatternWhereTheyCannotDiffer) {
  auto expect_same = [](const ModelConfig& rigid, const ModelConfig& tip, const char* what) {
    SCOPED_TRACE(what);
    ASSERT_EQ(rigid.effects.runout.helix, RunoutHelix::kRigidAxis);
    ASSERT_EQ(tip.effects.runout.helix, RunoutHelix::kTipPattern);
    const BothModels a = both_models(rigid);
    const BothModels b = both_models(tip);
    const double peak = peak_of(a.evaluator);
    EXPECT_GT(peak, 0.1);
    EXPECT_LE(max_difference(a.evaluator, b.evaluator), 1e-12 * peak);
    EXPECT_LE(max_difference(a.marching, b.marching), 1e-12 * peak);
  };
  ModelConfig full = reference_case(360);
  full.effects.deflection.enabled = false;  // the same root either way; keeps this test short
  full.effects.flank_wear.enabled = true;
  full.effects.flank_wear.wear_um = {4.0, 1.0};
  full.effects.runout.helix = RunoutHelix::kRigidAxis;
  ModelConfig tip = full;
  tip.effects.runout.helix = RunoutHelix::kTipPattern;

  ModelConfig rigid = full;
  rigid.effects.helix_lag.enabled = false;
  ModelConfig tip_case = tip;
  tip_case.effects.helix_lag.enabled = false;
  expect_same(rigid, tip_case, "helix lag off");

  rigid = full;
  rigid.effects.helix_lag.discs = 1;
  tip_case = tip;
  tip_case.effects.helix_lag.discs = 1;
  tip_case.effects.runout.angle_rad += 0.5 * helix_lag_total_rad(tip_case);
  expect_same(rigid, tip_case, "one disc, tip pattern at gamma + beta/2");

  rigid = full;
  rigid.effects.runout.offset_um = 0.0;
  tip_case = tip;
  tip_case.effects.runout.offset_um = 0.0;
  expect_same(rigid, tip_case, "rho = 0");

  rigid = full;
  rigid.tool.flutes = 1;
  rigid.effects.trochoidal.enabled = false;
  rigid.effects.flank_wear.wear_um = {4.0};
  rigid.effects.runout.offset_um = 5.0;
  tip_case = rigid;
  tip_case.effects.runout.helix = RunoutHelix::kTipPattern;
  expect_same(rigid, tip_case, "one flute, circular path");

  // ... and where they can differ, they do.
  const BothModels a = both_models(full);
  const BothModels b = both_models(tip);
  EXPECT_GT(max_difference(a.evaluator, b.evaluator), 0.01 * peak_of(a.evaluator));
}

// Closed form of the rigid-axis circular chip: one pass back, linear law without edge force,
// 2 flutes, 4 discs whose lags fall on the 0.5° grid (β = 8°: lag_i = 1°, 3°, 5°, 7°). Flute j
// at disc i, immersion θ_ij = φ − ψ_j − lag_i, cuts
//   h_ij = max(0, f_t·sin θ_ij + r_{j,i} − r_{j−1,i}),
//   r_{j,i} = √(R² + ρ² + 2Rρ·cos(γ + ψ_j + lag_i))
// with F_t = K_t·h·dz, F_n = K_n·h·dz, F_a = K_a·h·dz projected by [000] eq 7; the tip pattern
// is the same with lag_i left out of r. Both models, to 1e-12 N.
TEST(SteadyState, RigidAxisCircularChipHasEachDiscsRadiiInClosedForm) {
  ModelConfig c = without_effects(ModelConfig{});
  c.effects.runout.enabled = true;
  c.effects.runout.offset_um = 2.0;
  c.effects.runout.angle_rad = 1.2;  // cos(γ + lag) changes a lot over the discs
  c.effects.helix_lag.enabled = true;
  c.effects.helix_lag.discs = 4;
  c.tool.helix_deg = 30.0;
  const double radius_mm = c.tool.diameter_mm / 2.0;
  const double beta = 8.0 * kPi / 180.0;
  // [000] eq 4 inverted: a_p·tan λ = 2R·sin(β/2)
  c.process.axial_depth_mm = 2.0 * radius_mm * std::sin(beta / 2.0) / std::tan(kPi / 6.0);
  ASSERT_NEAR(helix_lag_total_rad(c), beta, 1e-14);
  c.material.law = ForceLawKind::kLinearEdge;
  c.material.linear_edge.k_te_N_per_mm = 0.0;
  c.material.linear_edge.k_ne_N_per_mm = 0.0;
  c.material.linear_edge.k_ac_N_per_mm2 = 200.0;
  const int steps = 720;
  c.resolution.steps_per_rev = steps;
  const auto& le = c.material.linear_edge;
  const double r_um = 1e3 * radius_mm;
  const double rho = c.effects.runout.offset_um;
  const double dz = c.process.axial_depth_mm / 4.0;
  for (RunoutHelix helix : {RunoutHelix::kRigidAxis, RunoutHelix::kTipPattern}) {
    SCOPED_TRACE(to_string(helix));
    c.effects.runout.helix = helix;
    auto cutting_radius = [&](int j, double lag) {
      const double angle =
          c.effects.runout.angle_rad + j * kPi + (helix == RunoutHelix::kRigidAxis ? lag : 0.0);
      return std::sqrt(r_um * r_um + rho * rho + 2.0 * r_um * rho * std::cos(angle));
    };
    const BothModels m = both_models(c);
    int compared = 0;
    for (int k = 0; k < steps; ++k) {
      const double phi = 2.0 * kPi * k / steps;
      std::array<double, 3> f = {0.0, 0.0, 0.0};
      bool at_an_edge = false;
      for (int i = 0; i < 4; ++i) {
        const double lag = (2 * i + 1) * kPi / 180.0;
        for (int j = 0; j < 2; ++j) {
          const double theta = std::fmod(phi - j * kPi - lag + 6.0 * kPi, 2.0 * kPi);
          at_an_edge = at_an_edge || std::fabs(theta) < 1e-9 || std::fabs(theta - kPi) < 1e-9 ||
                       std::fabs(theta - 2.0 * kPi) < 1e-9;
          if (theta > kPi) {
            continue;
          }
          const double h_um = c.process.feed_per_tooth_um * std::sin(theta) +
                              cutting_radius(j, lag) - cutting_radius(1 - j, lag);
          const double h = 1e-3 * std::max(h_um, 0.0);
          const double ft = le.k_tc_N_per_mm2 * h * dz;
          const double fn = le.k_nc_N_per_mm2 * h * dz;
          f[0] += -ft * std::cos(theta) - fn * std::sin(theta);
          f[1] += ft * std::sin(theta) - fn * std::cos(theta);
          f[2] += le.k_ac_N_per_mm2 * h * dz;
        }
      }
      if (at_an_edge) {
        continue;  // entry and exit: ±1e-16 in θ decides whether a chip r_j − r_k counts
      }
      ++compared;
      const auto uk = static_cast<std::size_t>(k);
      for (const ForceWaveform* w : {&m.evaluator, &m.marching}) {
        ASSERT_NEAR(w->fx_N[uk], f[0], 1e-12) << k;
        ASSERT_NEAR(w->fy_N[uk], f[1], 1e-12) << k;
        ASSERT_NEAR(w->fz_N[uk], f[2], 1e-12) << k;
      }
    }
    EXPECT_GT(compared, steps - 20);
  }
}

// What the rigid axis changes for identification (physics-notes, "What the force can tell about
// runout"): ρ·cos γ sets the flutes' radius difference 2ρ·cos γ; in the tip pattern ρ·sin γ
// reaches the force only through the trochoid's pitch term f_t·(2ρ/R)·sin γ/π, but on a rigid
// axis disc i sees 2ρ·cos(γ + lag_i) ≈ 2ρ·cos γ − 2ρ·sin γ·lag_i. Moving ρ·sin γ from 0 to 2 µm
// at ρ·cos γ = 1 µm ([000]'s case, 10 discs, β = 6.6°), as RMS of the change over RMS force:
//                                 tip pattern    rigid axis
//   circular path (lockstep)        0.00 %         5.7 %
//   trochoidal, multi-pass          1.2 %          6.1 %
// and at γ = 90° (a pure pitch error, ρ = 2 µm) the flutes' peaks differ by 0.57 % (tip) and
// 5.9 % (rigid). Without helix lag the two are the same model.
TEST(SteadyState, RhoSinGammaReachesTheForceThroughTheHelixOnARigidAxis) {
  auto flute_peak = [](const ForceWaveform& f, int flute) {
    const std::size_t half = f.fx_N.size() / 2;
    double peak = 0.0;
    for (std::size_t k = flute * half; k < (flute + 1) * half; ++k) {
      peak = std::max(peak, std::hypot(f.fx_N[k], f.fy_N[k]));
    }
    return peak;
  };
  for (bool trochoidal : {false, true}) {
    SCOPED_TRACE(trochoidal ? "trochoidal" : "circular");
    std::array<double, 2> change{};      // tip, rigid
    std::array<double, 2> flute_diff{};  // tip, rigid
    for (bool helix : {false, true}) {
      std::array<ForceWaveform, 2> without_helix;
      for (RunoutHelix mode : {RunoutHelix::kTipPattern, RunoutHelix::kRigidAxis}) {
        ModelConfig c = without_effects(ModelConfig{});
        for (const char* e : {"runout", "multi_pass"}) {
          set_effect(c, e, true);
        }
        c.effects.trochoidal.enabled = trochoidal;
        c.effects.helix_lag.enabled = helix;
        c.effects.runout.helix = mode;
        SteadyStateWorkspace ws;
        c.effects.runout.offset_um = 1.0;
        c.effects.runout.angle_rad = 0.0;
        const ForceWaveform a = evaluate_steady_state(c, 25000.0, 720, ws).mean;
        c.effects.runout.offset_um = std::sqrt(5.0);  // ρ·cos γ = 1 µm, ρ·sin γ = 2 µm
        c.effects.runout.angle_rad = std::atan2(2.0, 1.0);
        const ForceWaveform b = evaluate_steady_state(c, 25000.0, 720, ws).mean;
        c.effects.runout.offset_um = 2.0;
        c.effects.runout.angle_rad = kPi / 2.0;
        const ForceWaveform pitch = evaluate_steady_state(c, 25000.0, 720, ws).mean;
        const auto m = static_cast<std::size_t>(mode == RunoutHelix::kRigidAxis);
        if (!helix) {
          without_helix[m] = b;
          continue;
        }
        change[m] = rms_xy(b, &a) / rms_xy(a);
        flute_diff[m] = std::fabs(flute_peak(pitch, 0) - flute_peak(pitch, 1)) /
                        std::max(flute_peak(pitch, 0), flute_peak(pitch, 1));
      }
      if (!helix) {
        EXPECT_EQ(max_difference(without_helix[0], without_helix[1]), 0.0);
      }
    }
    const double tip = change[0];
    const double rigid = change[1];
    EXPECT_GT(rigid, 0.04);
    EXPECT_LT(rigid, 0.08);
    EXPECT_GT(flute_diff[1], 0.04);
    EXPECT_LT(flute_diff[0], 0.01);  // physics-notes: "well under 1 %"
    if (trochoidal) {
      EXPECT_GT(tip, 0.005);  // the pitch term
      EXPECT_GT(rigid, 3.0 * tip);
    } else {
      EXPECT_LT(tip, 1e-4);  // only through ρ² in the radii
    }
  }
}

// Continuous in the runout angle: the force moves in proportion to a small change of γ wherever
// γ + lag_i lies (including a pure pitch error, γ = ±90°), does not notice a turn of 2π, and
// meets the one-table geometry of ρ = 0 continuously as ρ → 0.
TEST(SteadyState, ForceIsContinuousInTheRunoutAngleOnARigidAxis) {
  ModelConfig c = without_effects(reference_case(720));
  for (const char* e : {"runout", "trochoidal", "multi_pass", "helix_lag"}) {
    set_effect(c, e, true);
  }
  c.material.law = ForceLawKind::kLinearEdge;
  c.material.linear_edge.k_te_N_per_mm = 0.0;
  c.material.linear_edge.k_ne_N_per_mm = 0.0;
  c.effects.runout.helix = RunoutHelix::kRigidAxis;
  SteadyStateWorkspace ws;
  for (double gamma : {0.58, kPi / 2.0, -kPi / 2.0 + 0.05, 3.1}) {
    SCOPED_TRACE(gamma);
    c.effects.runout.angle_rad = gamma;
    const ForceWaveform base = evaluate_steady_state(c, 25000.0, 720, ws).mean;
    std::array<double, 2> change{};
    for (int s = 0; s < 2; ++s) {
      ModelConfig d = c;
      d.effects.runout.angle_rad += s == 0 ? 1e-6 : 1e-5;
      change[static_cast<std::size_t>(s)] =
          max_difference(evaluate_steady_state(d, 25000.0, 720, ws).mean, base);
    }
    EXPECT_GT(change[0], 0.0);
    EXPECT_NEAR(change[1] / change[0], 10.0, 1.0);
    ModelConfig turned = c;
    turned.effects.runout.angle_rad = gamma > 0.0 ? gamma - 2.0 * kPi : gamma + 2.0 * kPi;
    EXPECT_LT(max_difference(evaluate_steady_state(turned, 25000.0, 720, ws).mean, base),
              1e-12 * peak_of(base));
  }
  c.effects.runout.offset_um = 0.0;
  const ForceWaveform none = evaluate_steady_state(c, 25000.0, 720, ws).mean;
  c.effects.runout.offset_um = 1e-7;
  const ForceWaveform tiny = evaluate_steady_state(c, 25000.0, 720, ws).mean;
  EXPECT_GT(max_difference(tiny, none), 0.0);
  EXPECT_LT(max_difference(tiny, none), 1e-6 * peak_of(none));
}

// [001] eqs 14-17 for a circular chip h = f_t·sin θ (no runout, one disc): A_c(θ) =
// f_t·r·(1 − cos θ); below h_min before the largest chip A_p = A_c(θ), above h_min A_p =
// A_c(θ₁) at the crossing θ₁ = asin(h_min/f_t), below h_min after it A_p = A_c(π) − A_c(θ);
// F = (K_s·h + K_p·A_p)·a_p. The evaluator integrates by trapezoids with the crossing
// interpolated (second order); the time-marching model sums rectangles and switches on grid
// steps (first order).
TEST(SteadyState, PloughedAreaFollowsAbeniEquations14To17) {
  ModelConfig c = without_effects(ModelConfig{});
  c.material.law = ForceLawKind::kLinearEdge;
  auto& le = c.material.linear_edge;
  le = LinearEdge{};
  le.k_tc_N_per_mm2 = 1000.0;
  le.k_nc_N_per_mm2 = 420.0;
  le.k_ac_N_per_mm2 = 60.0;
  le.ploughing_area = true;
  le.k_tp_N_per_mm3 = 4000.0;
  le.k_np_N_per_mm3 = 6000.0;
  le.k_ap_N_per_mm3 = 500.0;
  c.effects.min_chip.enabled = true;
  c.effects.min_chip.h_min_um = 1.0;
  const int steps = 720;
  const double ft = c.process.feed_per_tooth_um;
  const double r_mm = c.tool.diameter_mm / 2.0;
  const double ap = c.process.axial_depth_mm;
  const double crossing = std::asin(c.effects.min_chip.h_min_um / ft);
  auto cut_area = [&](double theta) { return 1e-3 * ft * r_mm * (1.0 - std::cos(theta)); };
  auto closed_form = [&](double phi, int axis) {
    double f = 0.0;
    for (int j = 0; j < 2; ++j) {
      const double theta = std::fmod(phi - j * kPi + 4.0 * kPi, 2.0 * kPi);
      if (theta > kPi) {
        continue;
      }
      const double h = ft * std::sin(theta);
      const double area = h >= c.effects.min_chip.h_min_um ? cut_area(crossing)
                          : theta < kPi / 2                ? cut_area(theta)
                                                           : cut_area(kPi) - cut_area(theta);
      const double t = (le.k_tc_N_per_mm2 * 1e-3 * h + le.k_tp_N_per_mm3 * area) * ap;
      const double n = (le.k_nc_N_per_mm2 * 1e-3 * h + le.k_np_N_per_mm3 * area) * ap;
      const double a = (le.k_ac_N_per_mm2 * 1e-3 * h + le.k_ap_N_per_mm3 * area) * ap;
      f += axis == 0   ? -t * std::cos(theta) - n * std::sin(theta)
           : axis == 1 ? t * std::sin(theta) - n * std::cos(theta)
                       : a;
    }
    return f;
  };
  SteadyStateWorkspace ws;
  const SteadyState& st = evaluate_steady_state(c, 25000.0, steps, ws);
  c.resolution.steps_per_rev = steps;
  MillingModel marching(c);
  marching.warm_up(3);
  double error = 0.0, marching_error = 0.0, peak = 0.0;
  for (int k = 0; k < steps; ++k) {
    const double phi = 2.0 * kPi * k / steps;
    const auto uk = static_cast<std::size_t>(k);
    const std::array<double, 3> e = {st.mean.fx_N[uk], st.mean.fy_N[uk], st.mean.fz_N[uk]};
    const std::array<double, 3> m = {marching.forces().fx_N[uk], marching.forces().fy_N[uk],
                                     marching.forces().fz_N[uk]};
    for (int a = 0; a < 3; ++a) {
      const double exact = closed_form(phi, a);
      peak = std::max(peak, std::fabs(exact));
      error = std::max(error, std::fabs(e[static_cast<std::size_t>(a)] - exact));
      marching_error = std::max(marching_error, std::fabs(m[static_cast<std::size_t>(a)] - exact));
    }
  }
  EXPECT_LT(error, 1e-4 * peak);
  EXPECT_LT(error, 0.1 * marching_error);
}

// No grid-quantised switch: as h_min grows, the crossing θ₁ moves across grid steps, and the
// evaluator's force follows smoothly; the time-marching model's jumps by a rectangle each time
// the first shearing step moves.
TEST(SteadyState, PloughedAreaMovesContinuouslyWithTheMinimumChip) {
  ModelConfig c = without_effects(ModelConfig{});
  c.material.law = ForceLawKind::kLinearEdge;
  c.material.linear_edge.ploughing_area = true;
  c.material.linear_edge.k_te_N_per_mm = 0.0;
  c.material.linear_edge.k_ne_N_per_mm = 0.0;
  c.material.linear_edge.k_tp_N_per_mm3 = 4000.0;
  c.material.linear_edge.k_np_N_per_mm3 = 6000.0;
  c.effects.min_chip.enabled = true;
  c.resolution.steps_per_rev = 720;
  SteadyStateWorkspace ws;
  double evaluator_step = 0.0, marching_step = 0.0;
  ForceWaveform previous, previous_marching;
  for (int i = 0; i <= 40; ++i) {
    c.effects.min_chip.h_min_um = 1.0 + 0.0025 * i;  // θ₁ moves by about 3 grid steps
    const ForceWaveform now = evaluate_steady_state(c, 25000.0, 720, ws).mean;
    MillingModel m(c);
    m.warm_up(3);
    if (i > 0) {
      evaluator_step = std::max(evaluator_step, max_difference(now, previous));
      marching_step = std::max(marching_step, max_difference(m.forces(), previous_marching));
    }
    previous = now;
    previous_marching = m.forces();
  }
  EXPECT_GT(evaluator_step, 0.0);
  EXPECT_LT(evaluator_step, 0.25 * marching_step);
}

// Accumulation ([002] eqs 11-12): at f_t = 0.4 µm and h_min = 0.9 µm the slot centre is cut
// every third pass with a chip of three feeds, a pattern of three revolutions. The cycle shows
// it: its revolutions differ and the tooth-passing frequency gets sub-harmonics.
TEST(SteadyState, AccumulationCycleSkipsPassesAndMakesSubharmonics) {
  ModelConfig c;
  c.effects.runout.enabled = false;
  c.effects.deflection.enabled = false;
  c.effects.helix_lag.enabled = false;
  c.effects.trochoidal.enabled = false;
  c.effects.min_chip.h_min_um = 0.9;
  c.process.feed_per_tooth_um = 0.4;
  const int steps = 720;
  SteadyStateWorkspace ws;
  const SteadyState& st = evaluate_steady_state(c, 25000.0, steps, ws);
  const int centre = steps / 4;  // θ = π/2
  EXPECT_EQ(ws.slot_period_revolutions(0, centre), 3);
  int removed = 0;
  for (long r = 0; r < 6; ++r) {
    for (int j = 0; j < 2; ++j) {
      if (ws.removed(j, centre, 1000 + r)) {
        ++removed;
        EXPECT_NEAR(ws.chip_um(j, centre, 1000 + r), 1.2, 1e-9);
      }
    }
  }
  EXPECT_EQ(removed, 4);
  ASSERT_GT(st.cycle_revolutions, 1);

  // The revolutions of the cycle differ from one another (which passes skip changes from
  // revolution to revolution). Which flute takes an accumulated chip at a slot is decided by the
  // cut's start (cut every second pass: always the same flute), so not even the mean revolution
  // need repeat every tooth period.
  double between = 0.0;
  for (std::size_t k = 0; k < static_cast<std::size_t>(steps); ++k) {
    between = std::max(between, std::fabs(st.revolution(0, 1)[k] - st.revolution(1, 1)[k]));
  }
  EXPECT_GT(between, 0.05);

  // Spectrum of the cycle (L revolutions): harmonics of the tooth-passing frequency are the
  // bins q = 2L·h; the rest are its sub-harmonics.
  const int n = st.cycle_revolutions * steps;
  const int tooth = 2 * st.cycle_revolutions;
  double sub = 0.0, all = 0.0;
  for (int q = 1; q <= 2 * tooth; ++q) {  // up to the second tooth harmonic
    std::complex<double> x = 0.0;
    for (int i = 0; i < n; ++i) {
      x += st.cycle.fy_N[static_cast<std::size_t>(i)] * std::polar(1.0, -2.0 * kPi * q * i / n);
    }
    all += std::norm(x);
    if (q % tooth != 0) {
      sub += std::norm(x);
    }
  }
  EXPECT_GT(sub, 1e-3 * all);
}

// The mean revolution is the mean of the cycle's revolutions (before and after the dynamometer,
// a linear filter), and a revolution of an exact cycle matches the time-marching model.
TEST(SteadyState, MeanIsTheCycleMeanAlsoThroughTheDynamometer) {
  for (bool dynamometer : {false, true}) {
    ModelConfig c = without_effects(reference_case(720));
    for (const char* e : {"runout", "multi_pass", "accumulation", "helix_lag"}) {
      set_effect(c, e, true);
    }
    c.effects.dynamometer.enabled = dynamometer;
    SteadyStateWorkspace ws;
    const SteadyState& st = evaluate_steady_state(c, 25000.0, 720, ws);
    ASSERT_TRUE(st.cycle_exact);
    ASSERT_GT(st.cycle_revolutions, 1);
    for (int a = 0; a < 3; ++a) {
      for (int k = 0; k < 720; ++k) {
        double mean = 0.0;
        for (int m = 0; m < st.cycle_revolutions; ++m) {
          mean += st.revolution(m, a)[static_cast<std::size_t>(k)] / st.cycle_revolutions;
        }
        const std::vector<double>& direct = a == 0   ? st.mean.fx_N
                                            : a == 1 ? st.mean.fy_N
                                                     : st.mean.fz_N;
        ASSERT_NEAR(direct[static_cast<std::size_t>(k)], mean, 1e-12) << a << " " << k;
      }
    }
  }
}

// The dynamometer as a periodic steady state in the frequency domain equals the time-marching
// model's resonance filtered sample by sample once settled (on a fine grid, where its bilinear
// discretisation is close to the continuous resonance the evaluator uses).
TEST(SteadyState, DynamometerEqualsTheSettledTimeDomainResonance) {
  ModelConfig c = without_effects(ModelConfig{});
  c.effects.runout.enabled = true;
  c.effects.dynamometer.enabled = true;
  c.effects.dynamometer.natural_hz = {2145.0, 2192.0, 3000.0};
  c.effects.dynamometer.damping_ratio = {0.05, 0.05, 0.05};
  c.material.power_law.k_ac_Nmm = 200.0;
  c.material.power_law.a_ac = 0.5;
  const int steps = 2880;
  c.resolution.steps_per_rev = steps;
  SteadyStateWorkspace ws;
  const SteadyState& st = evaluate_steady_state(c, c.process.spindle_rpm, steps, ws);
  MillingModel m(c);
  m.warm_up(80);
  const double peak = peak_of(m.forces());
  EXPECT_LT(max_difference(st.mean, m.forces()), 2e-3 * peak);
  c.effects.dynamometer.enabled = false;
  SteadyStateWorkspace plain_ws;
  const SteadyState& plain = evaluate_steady_state(c, c.process.spindle_rpm, steps, plain_ws);
  EXPECT_GT(max_difference(st.mean, plain.mean), 0.1 * peak);  // it does reshape the force
}

// With [000] Table 2's coefficients F_n falls at h_min (K_np·h_min^a_np > K_nc·h_min^a_nc), so
// near h_min the deflection balance h + (F_n(h) + F_w)/k = h_r has two roots. The evaluator
// takes the smallest (the tool stops at the first balance it meets going in); the
// time-marching model takes whichever its Newton start (the neighbouring step) leads to. The
// balance is solved to rounding (Halley's method in ln h, stopped below a step of 1e-7: ~1e-21
// left) for the power law, the linear edge law with [002]'s ploughing law below h_min (normal
// and tangential, or tangential alone) and Kronenberg's, on both regimes' branches; a chip held
// at h_min by a rise of F_n there has no balance and is left out. The linear edge law alone
// makes the balance a line, solved at once.
TEST(SteadyState, DeflectionTakesTheSmallestRootToRoundingForEachLaw) {
  ModelConfig table2;  // one disc, without accumulation or dynamometer
  table2.effects.helix_lag.enabled = false;
  table2.effects.accumulation.enabled = false;
  table2.effects.dynamometer.enabled = false;
  ModelConfig thin = table2;
  thin.process.feed_per_tooth_um = 2.0;  // more chips on both sides of h_min
  ModelConfig linear = thin;
  linear.material.law = ForceLawKind::kLinearEdge;
  linear.material.linear_edge.a_n_Nmm = 183.3;  // [002] eq 17 below h_min
  linear.material.linear_edge.b_n = 0.5;
  ModelConfig tangential_only = linear;  // F_n = 0 below h_min
  tangential_only.material.linear_edge.a_n_Nmm = 0.0;
  tangential_only.material.linear_edge.a_t_Nmm = 114.7;
  ModelConfig kronenberg = thin;
  kronenberg.material.law = ForceLawKind::kKronenberg;
  ModelConfig linear_edge = table2;  // [002] eq 18 on both sides of h_min: solved in closed form
  linear_edge.material.law = ForceLawKind::kLinearEdge;
  for (const ModelConfig& c : {table2, thin, linear, tangential_only, kronenberg, linear_edge}) {
    SCOPED_TRACE(to_string(c.material.law) + " at " + std::to_string(c.process.feed_per_tooth_um));
    const int steps = 720;
    SteadyStateWorkspace ws;
    evaluate_steady_state(c, 25000.0, steps, ws);
    const double h_min = c.effects.min_chip.h_min_um;
    const ForceLaw law(c.material, c.process.axial_depth_mm, h_min, true);
    const double k = c.effects.deflection.stiffness_N_per_um;
    const double dz = c.process.axial_depth_mm;
    int below = 0, above = 0, near_h_min = 0;
    for (int j = 0; j < 2; ++j) {
      for (int b = 0; b < steps; ++b) {
        const double hr = ws.rigid_chip_um(j, b);
        const double h = ws.chip_um(j, b);
        if (hr <= 0.0 || h <= 0.0 || h == h_min) {
          continue;
        }
        auto balance = [&](double x) { return x + law.normal_N(x, dz) / k - hr; };
        ASSERT_LT(std::fabs(balance(h)), 1e-13 * hr) << j << " " << b << " h " << h;
        for (int i = 0; i < 400; ++i) {  // no balance below h
          const double x = h * std::pow(1e-6, 1.0 - i / 400.0);
          ASSERT_LT(balance(x), 0.0) << j << " " << b << " " << x;
        }
        (h < h_min ? below : above) += 1;
        near_h_min += hr > h_min && hr < 1.5 * h_min ? 1 : 0;
      }
    }
    // [000]'s 4 µm/tooth: over 500 chips in contact; at 2 µm/tooth fewer passes cut.
    EXPECT_GT(below + above,
              c.process.feed_per_tooth_um == table2.process.feed_per_tooth_um ? 500 : 400);
    EXPECT_GT(below, 20);
    EXPECT_GT(above, 20);
    if (c.material.law == ForceLawKind::kPowerLaw) {
      EXPECT_GT(near_h_min, 0);  // F_n falls at h_min: balances just above it exist
    }
  }
}

// A law whose normal force falls with the chip — coefficients a fit tries on its way (PHM cut
// 1's diagnosis) — makes the balance G(h) = h + F_n(h)/k − h_r non-convex, with G' < 0: Halley's
// step left the bracket and ran to u = ln h = −1e293, a hundred underflowing exponentials an
// element (the diagnosis took 62 s, 24 s now). The step stays in the bracket: the chips are
// finite, within [0, h_r], and nothing underflows. With the linear edge law G is a falling
// line: the first balance met going in — the tool pushed back (no chip) where the edge force
// alone balances, else none short of the rigid chip, which it then cuts whole (a bisection had
// ended at the floor or the rigid chip, depending on where it started).
TEST(SteadyState, DeflectionStaysInItsBracketForAFallingNormalForce) {
  ModelConfig c;
  c.effects.helix_lag.enabled = false;
  c.effects.accumulation.enabled = false;
  c.effects.dynamometer.enabled = false;
  c.material.law = ForceLawKind::kLinearEdge;
  c.material.linear_edge.k_nc_N_per_mm2 = -40000.0;  // F_n falls 1.6 N per µm of chip
  c.material.linear_edge.k_ne_N_per_mm = 2.0;        // balances the chips below 1.6 µm alone
  c.effects.deflection.stiffness_N_per_um = 0.05;
  const int steps = 360;
  SteadyStateWorkspace ws;
  std::feclearexcept(FE_ALL_EXCEPT);
  evaluate_steady_state(c, 25000.0, steps, ws);
  EXPECT_FALSE(std::fetestexcept(FE_UNDERFLOW));
  int cutting = 0, pushed_back = 0, whole = 0;
  for (int j = 0; j < 2; ++j) {
    for (int b = 0; b < steps; ++b) {
      const double hr = ws.rigid_chip_um(j, b);
      const double h = ws.chip_um(j, b);
      ASSERT_TRUE(std::isfinite(h)) << j << " " << b;
      ASSERT_GE(h, 0.0);
      ASSERT_LE(h, std::max(hr, 0.0) * (1.0 + 1e-12) + 1e-300) << j << " " << b;
      cutting += hr > 0.0 ? 1 : 0;
      if (hr > 0.0) {
        const auto& le = c.material.linear_edge;
        const double a_p = c.process.axial_depth_mm;
        const auto balance = [&](double x) {
          return x + (le.k_nc_N_per_mm2 * 1e-3 * x + le.k_ne_N_per_mm) * a_p / 0.05 - hr;
        };
        if (h == 0.0) {
          pushed_back += 1;
          EXPECT_GE(balance(1e-6 * hr), 0.0) << j << " " << b;
        } else {
          whole += 1;
          EXPECT_EQ(h, hr) << j << " " << b;
          EXPECT_LT(balance(1e-6 * hr), 0.0) << j << " " << b;
        }
      }
    }
  }
  EXPECT_GT(cutting, 100);
  EXPECT_GT(pushed_back, 0);
  EXPECT_GT(whole, 0);
}

// physics-notes: at 10 µm/tooth the rigid chips of the two flutes are 13.0 and 7.0 µm; the
// material-conserving deflection brings them to about 12.6 and 7.4 µm, still two feeds in all.
TEST(SteadyState, DeflectionBalancesTheFlutesChipsAsPhysicsNotesReport) {
  ModelConfig c;
  c.process.feed_per_tooth_um = 10.0;
  c.effects.dynamometer.enabled = false;
  auto max_chip = [](const SteadyStateWorkspace& ws, int flute) {
    double h = 0.0;
    for (int m = 0; m < ws.result().cycle_revolutions; ++m) {
      for (int b = 0; b < ws.result().steps_per_rev; ++b) {
        h = std::max(h, ws.chip_um(flute, b, m));
      }
    }
    return h;
  };
  c.effects.deflection.enabled = false;
  SteadyStateWorkspace rigid;
  evaluate_steady_state(c, 25000.0, 720, rigid);
  EXPECT_NEAR(max_chip(rigid, 0), 13.0, 0.05);
  EXPECT_NEAR(max_chip(rigid, 1), 7.0, 0.05);
  c.effects.deflection.enabled = true;
  SteadyStateWorkspace flexible;
  evaluate_steady_state(c, 25000.0, 720, flexible);
  EXPECT_NEAR(max_chip(flexible, 0), 12.6, 0.1);
  EXPECT_NEAR(max_chip(flexible, 1), 7.4, 0.1);
  EXPECT_NEAR(max_chip(flexible, 0) + max_chip(flexible, 1), 20.0, 0.1);
}

// Separable least squares: with the chips fixed (no deflection) the force is the basis weighted
// by the law's coefficients plus the offset, for every law, through the dynamometer and with
// flank wear; with deflection there is no such basis.
TEST(SteadyState, ForceBasisRebuildsTheForce) {
  std::vector<ModelConfig> configs;
  ModelConfig c = reference_case(720);
  c.effects.deflection.enabled = false;
  c.effects.dynamometer.enabled = true;
  c.effects.flank_wear.enabled = true;
  c.effects.flank_wear.wear_um = {5.0, 2.0};
  c.material.power_law.k_ac_Nmm = 150.0;
  c.material.power_law.a_ac = 0.6;
  configs.push_back(c);  // power law, two regimes, accumulation
  c.material.law = ForceLawKind::kLinearEdge;
  c.material.linear_edge.a_t_Nmm = 114.7;  // [002] eq 17 below h_min: in the offset
  c.material.linear_edge.a_n_Nmm = 183.3;
  c.material.linear_edge.b_t = c.material.linear_edge.b_n = 0.5;
  configs.push_back(c);
  c.material.linear_edge.ploughing_area = true;
  c.material.linear_edge.k_tp_N_per_mm3 = 4000.0;
  c.material.linear_edge.k_np_N_per_mm3 = 6000.0;
  c.material.linear_edge.k_ap_N_per_mm3 = 300.0;
  configs.push_back(c);
  c.material.law = ForceLawKind::kKronenberg;
  configs.push_back(c);
  for (const ModelConfig& config : configs) {
    SCOPED_TRACE(to_string(config.material.law) +
                 (config.material.linear_edge.ploughing_area ? " area" : ""));
    SteadyStateWorkspace ws;
    const ForceWaveform force = evaluate_steady_state(config, 25000.0, 720, ws).mean;
    const ForceBasis& basis = evaluate_force_basis(config, 25000.0, 720, ws);
    ASSERT_GT(basis.columns, 0);
    const auto& le = config.material.linear_edge;
    const auto& pl = config.material.power_law;
    ForceWaveform rebuilt = basis.offset;
    for (int col = 0; col < basis.columns; ++col) {
      const std::string name = basis.names[static_cast<std::size_t>(col)];
      const double k = name == "k_tc_N_per_mm2"   ? le.k_tc_N_per_mm2
                       : name == "k_nc_N_per_mm2" ? le.k_nc_N_per_mm2
                       : name == "k_ac_N_per_mm2" ? le.k_ac_N_per_mm2
                       : name == "k_te_N_per_mm"  ? le.k_te_N_per_mm
                       : name == "k_ne_N_per_mm"  ? le.k_ne_N_per_mm
                       : name == "k_ae_N_per_mm"  ? le.k_ae_N_per_mm
                       : name == "k_tp_N_per_mm3" ? le.k_tp_N_per_mm3
                       : name == "k_np_N_per_mm3" ? le.k_np_N_per_mm3
                       : name == "k_ap_N_per_mm3" ? le.k_ap_N_per_mm3
                       : name == "k_tc_Nmm"       ? pl.k_tc_Nmm
                       : name == "k_nc_Nmm"       ? pl.k_nc_Nmm
                       : name == "k_ac_Nmm"       ? pl.k_ac_Nmm
                       : name == "k_tp_Nmm"       ? pl.k_tp_Nmm
                       : name == "k_np_Nmm"       ? pl.k_np_Nmm
                       : name == "k_ap_Nmm"       ? pl.k_ap_Nmm
                       : name == "k_s0_N_per_mm2" ? config.material.kronenberg.k_s0_N_per_mm2
                                                  : std::nan("");
      ASSERT_FALSE(std::isnan(k)) << name;
      const ForceWaveform& u = basis.unit[static_cast<std::size_t>(col)];
      for (std::size_t i = 0; i < 720; ++i) {
        rebuilt.fx_N[i] += k * u.fx_N[i];
        rebuilt.fy_N[i] += k * u.fy_N[i];
        rebuilt.fz_N[i] += k * u.fz_N[i];
      }
    }
    EXPECT_LT(max_difference(rebuilt, force), 1e-12 * peak_of(force));
    EXPECT_GT(peak_of(basis.offset), 0.0);  // flank wear
  }
  SteadyStateWorkspace ws;
  EXPECT_THROW(evaluate_force_basis(reference_case(720), 25000.0, 720, ws), std::invalid_argument);
}

// Pure: the same arguments give the same result whatever the workspace evaluated before.
TEST(SteadyState, ResultDependsOnTheArgumentsOnly) {
  ModelConfig a = reference_case(360);
  a.effects.flank_wear.enabled = true;
  a.effects.flank_wear.wear_um = {4.0};
  ModelConfig b = a;
  b.process.feed_per_tooth_um = 2.5;
  b.effects.runout.offset_um = 0.7;
  SteadyStateWorkspace fresh;
  const ForceWaveform first = evaluate_steady_state(a, 25000.0, 360, fresh).mean;
  SteadyStateWorkspace used;
  evaluate_steady_state(b, 24000.0, 360, used);
  const ForceWaveform fine = evaluate_steady_state(a, 26000.0, 720, used).mean;
  SteadyStateWorkspace fine_alone;
  EXPECT_EQ(max_difference(evaluate_steady_state(a, 26000.0, 720, fine_alone).mean, fine), 0.0);
  const ForceWaveform again = evaluate_steady_state(a, 25000.0, 360, used).mean;
  EXPECT_EQ(max_difference(first, again), 0.0);

  // A workspace keeps the immersion tables across evaluations while only the runout or the
  // coefficients change (a fit); a change of anything they depend on — the engaged arc, the
  // helix, the flutes' pitch, pass memory — must remake them.
  std::vector<ModelConfig> variants(6, a);
  variants[0].process.operation = Operation::kDownMilling;
  variants[0].process.radial_depth_mm = 0.1;
  variants[1].process.operation = Operation::kUpMilling;
  variants[1].process.radial_depth_mm = 0.2;
  variants[2].effects.helix_lag.enabled = false;
  variants[3].tool.pitch_deg = {170.3, 189.7};
  variants[4].tool.pitch_deg = {170.3, 189.7};  // without pass memory: its own immersion grid
  variants[4].effects.deflection.enabled = false;
  variants[4].effects.accumulation.enabled = false;
  variants[5].tool.helix_deg = 45.0;  // the same discs, a longer lag
  for (std::size_t v = 0; v < variants.size(); ++v) {
    SCOPED_TRACE("variant " + std::to_string(v));
    SteadyStateWorkspace alone;
    const ForceWaveform expected = evaluate_steady_state(variants[v], 25000.0, 360, alone).mean;
    evaluate_steady_state(a, 25000.0, 360, used);
    const ForceWaveform after_a = evaluate_steady_state(variants[v], 25000.0, 360, used).mean;
    EXPECT_EQ(max_difference(expected, after_a), 0.0);
    EXPECT_GT(max_difference(expected, first), 1e-3 * peak_of(first));  // a real change
    const ForceWaveform a_again = evaluate_steady_state(a, 25000.0, 360, used).mean;
    EXPECT_EQ(max_difference(first, a_again), 0.0);
  }
}

TEST(SteadyState, FeedRateStaysFixedAtTheActualSpeed) {
  ModelConfig commanded;
  commanded.process.spindle_rpm = 25000.0;
  commanded.process.feed_per_tooth_um = 4.0;
  const ModelConfig actual = at_actual_speed(commanded, 25252.0);
  EXPECT_EQ(actual.process.spindle_rpm, 25252.0);
  EXPECT_NEAR(actual.process.feed_per_tooth_um, 4.0 * 25000.0 / 25252.0, 1e-15);
  EXPECT_NEAR(actual.process.feed_per_tooth_um * actual.process.spindle_rpm,
              commanded.process.feed_per_tooth_um * commanded.process.spindle_rpm, 1e-9);
  EXPECT_THROW(static_cast<void>(at_actual_speed(commanded, 0.0)), std::invalid_argument);
}

// The lockstep's rebuild at a new speed — the configuration at that speed, the steady state,
// the monitor's low-pass applied to each axis (H or |H|²), the basis for a fitter — allocates
// nothing once the workspace is set up; nor does the full model (mean revolution).
TEST(SteadyState, EvaluationAllocatesNothingAfterSetUp) {
  ModelConfig commanded = without_effects(ModelConfig{});
  commanded.effects.runout.enabled = true;
  commanded.effects.helix_lag.enabled = true;
  commanded.effects.helix_lag.discs = 5;
  commanded.material.law = ForceLawKind::kLinearEdge;
  ModelConfig at_speed = commanded;
  SteadyStateWorkspace ws(commanded, 720);
  PeriodicResponse response(720);
  const auto design = signal::ButterworthDesign::lowpass(50000.0, 3300.0, 4);
  std::vector<std::complex<double>> gains(static_cast<std::size_t>(response.harmonics()));
  std::array<std::vector<double>, 3> filtered;
  for (auto& f : filtered) {
    f.resize(720);
  }
  at_actual_speed(commanded, 25252.0, at_speed);
  evaluate_steady_state(at_speed, 25252.0, 720, ws, SteadyStateOutput::kMean);
  {
    test::AllocationCounter counter;
    for (double rpm : {25300.0, 24800.0}) {
      at_actual_speed(commanded, rpm, at_speed);
      const SteadyState& st =
          evaluate_steady_state(at_speed, rpm, 720, ws, SteadyStateOutput::kMean);
      for (ResponseUse use : {ResponseUse::kComplex, ResponseUse::kPower}) {
        harmonic_gains([&](double f) { return design.response(f); }, rpm / 60.0, use, gains);
        const std::array<const std::vector<double>*, 3> axes = {&st.mean.fx_N, &st.mean.fy_N,
                                                                &st.mean.fz_N};
        for (std::size_t a = 0; a < 3; ++a) {
          std::copy(axes[a]->begin(), axes[a]->end(), filtered[a].begin());
          response.apply(filtered[a], gains);
        }
      }
      evaluate_force_basis(at_speed, rpm, 720, ws);
    }
    EXPECT_EQ(counter.allocations(), 0);
  }
  {
    // Switching runout on gives every disc its own chip table (rigid axis): room for them was
    // made when the workspace was sized.
    ModelConfig rigid = commanded;
    rigid.effects.runout.helix = RunoutHelix::kRigidAxis;
    ModelConfig no_runout = rigid;
    no_runout.effects.runout.enabled = false;
    SteadyStateWorkspace off_ws(no_runout, 720);
    evaluate_steady_state(no_runout, 25000.0, 720, off_ws, SteadyStateOutput::kMean);
    test::AllocationCounter counter;
    evaluate_steady_state(rigid, 25000.0, 720, off_ws, SteadyStateOutput::kMean);
    EXPECT_EQ(counter.allocations(), 0);
  }
  ModelConfig full;
  full.effects.dynamometer.enabled = true;
  full.effects.flank_wear.enabled = true;
  full.effects.flank_wear.wear_um = {5.0, 3.0};
  SteadyStateWorkspace full_ws(full, 720);
  evaluate_steady_state(full, 25000.0, 720, full_ws, SteadyStateOutput::kMean);
  full.effects.runout.offset_um = 1.7;
  test::AllocationCounter counter;
  evaluate_steady_state(full, 25252.0, 720, full_ws, SteadyStateOutput::kMean);
  EXPECT_EQ(counter.allocations(), 0);
}

TEST(SteadyState, RejectsBadArguments) {
  SteadyStateWorkspace ws;
  const ModelConfig c;
  EXPECT_THROW(evaluate_steady_state(c, 0.0, 720, ws), std::invalid_argument);
  EXPECT_THROW(evaluate_steady_state(c, 25000.0, 10, ws), std::invalid_argument);
  ModelConfig bad = c;
  bad.tool.pitch_deg = {100.0, 100.0};
  EXPECT_THROW(evaluate_steady_state(bad, 25000.0, 720, ws), config::ConfigError);
  evaluate_steady_state(c, 25000.0, 720, ws);
  EXPECT_THROW(static_cast<void>(ws.chip_um(2, 0)), std::out_of_range);
  EXPECT_THROW(static_cast<void>(ws.chip_um(0, 720)), std::out_of_range);
  EXPECT_THROW(static_cast<void>(ws.result().revolution(ws.result().cycle_revolutions, 0)),
               std::out_of_range);
}

}  // namespace
}  // namespace millwatch::model
