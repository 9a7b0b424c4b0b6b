// A window's identified runout on LCM (runout_estimate_t): every field from the fit, the
// geometric α included (it was a fixed 0), and a failed fit says why instead of numbers. The
// pipeline's status (pipeline_status5_t) carries what the summary counts.

#include "msgs/lcm_convert.hpp"

#include <gtest/gtest.h>

#include <string>

namespace millwatch::messaging {
namespace {

identify::IdentifiedWindow window() {
  identify::IdentifiedWindow w;
  w.revolution = 59;
  w.utime_us = 140000;
  w.window_revolutions = 30;
  w.fit.ok = true;
  w.fit.config.tool.flutes = 3;
  w.fit.rho_um = {"rho_um", 0.8, 0.015};
  w.fit.gamma_rad = {"gamma_rad", -0.7, 0.02};
  w.fit.cutting_radius_um = {{"r_ce1_um", 250.6, 0.01}, {"r_ce2_um", 249.9, 0.01}};
  w.fit.alpha_deg = {"alpha_deg", 120.24, 0.006};
  return w;
}

TEST(LcmConvert, ARunoutEstimateCarriesTheFitsGeometricAlpha) {
  const runout_estimate_t m = runout_estimate(window());
  EXPECT_TRUE(m.valid);
  EXPECT_EQ(m.revolution, 59);
  EXPECT_EQ(m.window_revolutions, 30);
  EXPECT_EQ(m.offset_um, 0.8);
  EXPECT_EQ(m.angle_rad, -0.7);
  EXPECT_EQ(m.r_ce1_um, 250.6);
  EXPECT_EQ(m.r_ce2_um, 249.9);
  EXPECT_EQ(m.alpha_deg, 120.24);
}

// A fit on a flute's contact edge: offset_um is the least runout the force allows, and the
// method says so.
TEST(LcmConvert, ARunoutThatIsALowerBoundSaysSo) {
  EXPECT_EQ(runout_estimate(window()).method,
            "window fit (flute 0 = CE1, the flute with the largest cut)");
  identify::IdentifiedWindow w = window();
  w.fit.runout_at_contact_edge = true;
  const runout_estimate_t m = runout_estimate(w);
  EXPECT_TRUE(m.valid);
  EXPECT_EQ(m.offset_um, 0.8);
  EXPECT_EQ(m.method,
            "window fit (flute 0 = CE1, the flute with the largest cut); at a flute's contact "
            "edge: offset_um is a lower bound (a flute cuts nothing beyond it)");
  w.fit.edge_flute = 2;  // three flutes: CE3 idle, its deficit to CE2 the bound
  EXPECT_EQ(runout_estimate(w).method,
            "window fit (flute 0 = CE1, the flute with the largest cut); at a flute's contact "
            "edge: offset_um is a lower bound (a flute cuts nothing beyond it); CE3 cuts "
            "nothing: its radius lies at least a chip below the flute's before it");
  w.fit.config.tool.flutes = 2;
  w.fit.edge_flute = 1;
  EXPECT_EQ(runout_estimate(w).method,
            "window fit (flute 0 = CE1, the flute with the largest cut); at a flute's contact "
            "edge: offset_um is a lower bound (a flute cuts nothing beyond it), and so is "
            "r_CE1 − r_CE2");
}

TEST(LcmConvert, AFailedFitSaysWhy) {
  identify::IdentifiedWindow w = window();
  w.fit.ok = false;
  w.fit.message = "too few harmonics";
  const runout_estimate_t m = runout_estimate(w);
  EXPECT_FALSE(m.valid);
  EXPECT_EQ(m.method, "window fit failed: too few harmonics");
  EXPECT_EQ(m.alpha_deg, 0.0);
}

// A revolution that lost a tooth event (valid false) has no α, flute periods or ΔFy: 0 with the
// flag down, as the README promises, not the meter's leftovers; one without both CE1 events has
// no period either. A valid revolution carries them all.
TEST(LcmConvert, WhatARevolutionDidNotMeasureIsZeroWithItsFlagDown) {
  monitor::RevolutionRecord r;
  r.revolution = 86;
  r.spindle_rpm = 25252.0;
  auto& m = r.measured;
  m.flutes = 2;
  m.period_s = 60.0 / 25252.0;
  m.flute_period_s = {0.0013, 0.0011};
  m.alpha_deg = 183.8;
  m.delta_fy_N = 0.751;
  m.bounded = true;
  m.valid = true;
  const tooth_periods2_t ok = tooth_periods(r);
  EXPECT_EQ(ok.alpha_deg, 183.8);
  EXPECT_EQ(ok.flute_period_s[1], 0.0011);
  EXPECT_EQ(flute_peaks(r).delta_fy_N, 0.751);

  m.valid = false;  // bounded: CE2's event missing
  const tooth_periods2_t lost = tooth_periods(r);
  EXPECT_FALSE(lost.valid);
  EXPECT_EQ(lost.alpha_deg, 0.0);
  ASSERT_EQ(lost.flute_period_s.size(), 2u);
  EXPECT_EQ(lost.flute_period_s[0], 0.0);
  EXPECT_EQ(lost.flute_period_s[1], 0.0);
  EXPECT_EQ(lost.period_s, 60.0 / 25252.0);  // its bounds were found
  EXPECT_EQ(lost.spindle_rpm, 25252.0);
  EXPECT_EQ(flute_peaks(r).delta_fy_N, 0.0);

  m.bounded = false;
  EXPECT_EQ(tooth_periods(r).period_s, 0.0);
}

// What the alert engine held at a changed speed, the identifications the model took, refused or
// never took (superseded) and the flutes' relabellings reach the daemon's status as they reach
// replay's summary (they were summary-only).
TEST(LcmConvert, TheStatusCarriesTheHeldRevolutionsTheIdentificationsAndTheRelabellings) {
  monitor::PipelineStatus s;
  s.revolutions = 1000;
  s.alert_held_revolutions = 502;
  s.alerts_holding = true;
  s.identifications_taken = 12;
  s.identifications_rejected = 3;
  s.identifications_superseded = 4;
  s.flutes_relabelled = 2;
  s.relabelled_from_revolution = 244;
  const pipeline_status5_t m = pipeline_status(s, 7, 100, 1);
  EXPECT_EQ(m.seq, 7);
  EXPECT_EQ(m.revolutions, 1000);
  EXPECT_EQ(m.alert_held_revolutions, 502);
  EXPECT_TRUE(m.alerts_holding);
  EXPECT_EQ(m.identifications_taken, 12);
  EXPECT_EQ(m.identifications_rejected, 3);
  EXPECT_EQ(m.identifications_superseded, 4);
  EXPECT_EQ(m.flutes_relabelled, 2);
  EXPECT_EQ(m.relabelled_from_revolution, 244);
  EXPECT_EQ(m.messages_published, 100);
  EXPECT_EQ(m.messages_dropped, 1);
}

}  // namespace
}  // namespace millwatch::messaging
