#include "core/model/model_config.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "core/config/json_reader.hpp"

namespace millwatch::model {
namespace {

using config::closed;
using config::non_negative;
using config::ObjectReader;
using config::positive;

constexpr double kBigCoefficient = 1e7;

Tool read_tool(ObjectReader r) {
  Tool t;
  t.diameter_mm = r.number("diameter_mm", t.diameter_mm, positive(50.0, "mm"));
  t.flutes = r.integer("flutes", t.flutes, 1, 8);
  t.helix_deg = r.number("helix_deg", t.helix_deg, closed(0.0, 60.0, "deg"));
  t.edge_radius_um = r.number("edge_radius_um", t.edge_radius_um, non_negative(100.0, "um"));
  t.pitch_deg = r.numbers("pitch_deg", {}, {0.0, 360.0, true, true, "deg"}, 0, 8);
  r.finish();
  return t;
}

Operation parse_operation(const std::string& s) {
  if (s == "up") {
    return Operation::kUpMilling;
  }
  if (s == "down") {
    return Operation::kDownMilling;
  }
  return Operation::kSlot;
}

Process read_process(ObjectReader r) {
  Process p;
  p.operation = parse_operation(r.choice("operation", "slot", {"slot", "up", "down"}));
  p.spindle_rpm = r.number("spindle_rpm", p.spindle_rpm, positive(200000.0, "rpm"));
  p.feed_per_tooth_um =
      r.number("feed_per_tooth_um", p.feed_per_tooth_um, positive(1000.0, "um/tooth"));
  p.axial_depth_mm = r.number("axial_depth_mm", p.axial_depth_mm, positive(20.0, "mm"));
  p.radial_depth_mm = r.number("radial_depth_mm", p.radial_depth_mm, positive(50.0, "mm"));
  r.finish();
  return p;
}

PowerLaw read_power_law(ObjectReader r) {
  PowerLaw c;
  const auto k = non_negative(kBigCoefficient, "N/mm^(1+a)");
  const auto a = positive(2.0);
  c.k_tc_Nmm = r.number("k_tc_Nmm", c.k_tc_Nmm, k);
  c.a_tc = r.number("a_tc", c.a_tc, a);
  c.k_nc_Nmm = r.number("k_nc_Nmm", c.k_nc_Nmm, k);
  c.a_nc = r.number("a_nc", c.a_nc, a);
  c.k_tp_Nmm = r.number("k_tp_Nmm", c.k_tp_Nmm, k);
  c.a_tp = r.number("a_tp", c.a_tp, a);
  c.k_np_Nmm = r.number("k_np_Nmm", c.k_np_Nmm, k);
  c.a_np = r.number("a_np", c.a_np, a);
  c.k_ac_Nmm = r.number("k_ac_Nmm", c.k_ac_Nmm, k);
  c.a_ac = r.number("a_ac", c.a_ac, a);
  c.k_ap_Nmm = r.number("k_ap_Nmm", c.k_ap_Nmm, k);
  c.a_ap = r.number("a_ap", c.a_ap, a);
  r.finish();
  return c;
}

LinearEdge read_linear_edge(ObjectReader r) {
  LinearEdge c;
  const auto k2 = closed(-kBigCoefficient, kBigCoefficient, "N/mm^2");
  const auto k1 = closed(-kBigCoefficient, kBigCoefficient, "N/mm");
  const auto k3 = non_negative(1e9, "N/mm^3");
  const auto kp = non_negative(kBigCoefficient, "N/mm^(1+B)");
  const auto b = positive(2.0);
  c.k_tc_N_per_mm2 = r.number("k_tc_N_per_mm2", c.k_tc_N_per_mm2, k2);
  c.k_nc_N_per_mm2 = r.number("k_nc_N_per_mm2", c.k_nc_N_per_mm2, k2);
  c.k_ac_N_per_mm2 = r.number("k_ac_N_per_mm2", c.k_ac_N_per_mm2, k2);
  c.k_te_N_per_mm = r.number("k_te_N_per_mm", c.k_te_N_per_mm, k1);
  c.k_ne_N_per_mm = r.number("k_ne_N_per_mm", c.k_ne_N_per_mm, k1);
  c.k_ae_N_per_mm = r.number("k_ae_N_per_mm", c.k_ae_N_per_mm, k1);
  c.ploughing_area = r.choice("ploughing", "edge", {"edge", "area"}) == "area";
  c.k_tp_N_per_mm3 = r.number("k_tp_N_per_mm3", c.k_tp_N_per_mm3, k3);
  c.k_np_N_per_mm3 = r.number("k_np_N_per_mm3", c.k_np_N_per_mm3, k3);
  c.k_ap_N_per_mm3 = r.number("k_ap_N_per_mm3", c.k_ap_N_per_mm3, k3);
  c.a_t_Nmm = r.number("a_t_Nmm", c.a_t_Nmm, kp);
  c.b_t = r.number("b_t", c.b_t, b);
  c.a_n_Nmm = r.number("a_n_Nmm", c.a_n_Nmm, kp);
  c.b_n = r.number("b_n", c.b_n, b);
  c.a_a_Nmm = r.number("a_a_Nmm", c.a_a_Nmm, kp);
  c.b_a = r.number("b_a", c.b_a, b);
  r.finish();
  return c;
}

Kronenberg read_kronenberg(ObjectReader r) {
  Kronenberg c;
  c.k_s0_N_per_mm2 =
      r.number("k_s0_N_per_mm2", c.k_s0_N_per_mm2, positive(kBigCoefficient, "N/mm^2"));
  c.m = r.number("m", c.m, {1.0, 100.0, true, false, ""});
  c.radial_ratio = r.number("radial_ratio", c.radial_ratio, non_negative(10.0));
  c.axial_ratio = r.number("axial_ratio", c.axial_ratio, closed(-10.0, 10.0));
  r.finish();
  return c;
}

Material read_material(ObjectReader r) {
  Material m;
  m.name = r.string("name", m.name);
  const std::string law = r.choice("law", "power_law", {"power_law", "linear_edge", "kronenberg"});
  m.law = law == "linear_edge"  ? ForceLawKind::kLinearEdge
          : law == "kronenberg" ? ForceLawKind::kKronenberg
                                : ForceLawKind::kPowerLaw;
  m.power_law = read_power_law(r.object("power_law"));
  m.linear_edge = read_linear_edge(r.object("linear_edge"));
  m.kronenberg = read_kronenberg(r.object("kronenberg"));
  r.finish();
  return m;
}

Effects read_effects(ObjectReader r, int flutes) {
  Effects e;
  {
    auto s = r.object("runout");
    e.runout.enabled = s.boolean("enabled", e.runout.enabled);
    e.runout.offset_um = s.number("offset_um", e.runout.offset_um, non_negative(100.0, "um"));
    e.runout.angle_rad = s.number("angle_rad", e.runout.angle_rad,
                                  closed(-2.0 * std::numbers::pi, 2.0 * std::numbers::pi, "rad"));
    e.runout.helix =
        s.choice("helix", to_string(e.runout.helix), {"rigid_axis", "tip_pattern"}) == "tip_pattern"
            ? RunoutHelix::kTipPattern
            : RunoutHelix::kRigidAxis;
    s.finish();
  }
  {
    auto s = r.object("trochoidal");
    e.trochoidal.enabled = s.boolean("enabled", e.trochoidal.enabled);
    s.finish();
  }
  {
    auto s = r.object("multi_pass");
    e.multi_pass.enabled = s.boolean("enabled", e.multi_pass.enabled);
    e.multi_pass.passes = s.integer("passes", e.multi_pass.passes, 0, 64);
    s.finish();
  }
  {
    auto s = r.object("min_chip");
    e.min_chip.enabled = s.boolean("enabled", e.min_chip.enabled);
    e.min_chip.h_min_um = s.number("h_min_um", e.min_chip.h_min_um, non_negative(50.0, "um"));
    s.finish();
  }
  {
    auto s = r.object("accumulation");
    e.accumulation.enabled = s.boolean("enabled", e.accumulation.enabled);
    s.finish();
  }
  {
    auto s = r.object("deflection");
    e.deflection.enabled = s.boolean("enabled", e.deflection.enabled);
    e.deflection.stiffness_N_per_um =
        s.number("stiffness_N_per_um", e.deflection.stiffness_N_per_um, positive(1e6, "N/um"));
    s.finish();
  }
  {
    auto s = r.object("helix_lag");
    e.helix_lag.enabled = s.boolean("enabled", e.helix_lag.enabled);
    e.helix_lag.discs = s.integer("discs", e.helix_lag.discs, 1, 200);
    s.finish();
  }
  {
    auto s = r.object("flank_wear");
    e.flank_wear.enabled = s.boolean("enabled", e.flank_wear.enabled);
    e.flank_wear.wear_um = s.numbers("wear_um", e.flank_wear.wear_um, non_negative(2000.0, "um"), 1,
                                     static_cast<std::size_t>(flutes));
    e.flank_wear.k_wt_N_per_mm2 = s.number("k_wt_N_per_mm2", e.flank_wear.k_wt_N_per_mm2,
                                           non_negative(kBigCoefficient, "N/mm^2"));
    e.flank_wear.k_wn_N_per_mm2 = s.number("k_wn_N_per_mm2", e.flank_wear.k_wn_N_per_mm2,
                                           non_negative(kBigCoefficient, "N/mm^2"));
    s.finish();
  }
  {
    auto s = r.object("dynamometer");
    e.dynamometer.enabled = s.boolean("enabled", e.dynamometer.enabled);
    const std::vector<double> fn(e.dynamometer.natural_hz.begin(), e.dynamometer.natural_hz.end());
    const std::vector<double> z(e.dynamometer.damping_ratio.begin(),
                                e.dynamometer.damping_ratio.end());
    const auto fn_read = s.numbers("natural_hz", fn, positive(1e6, "Hz"), 3, 3);
    const auto z_read = s.numbers("damping_ratio", z, positive(5.0), 3, 3);
    for (int i = 0; i < 3; ++i) {
      e.dynamometer.natural_hz[i] = fn_read[i];
      e.dynamometer.damping_ratio[i] = z_read[i];
    }
    s.finish();
  }
  r.finish();
  return e;
}

std::string join(const std::string& path, const char* key) {
  return path.empty() ? std::string(key) : path + "." + key;
}

}  // namespace

std::string to_string(Operation op) {
  switch (op) {
    case Operation::kUpMilling:
      return "up";
    case Operation::kDownMilling:
      return "down";
    case Operation::kSlot:
      break;
  }
  return "slot";
}

std::string to_string(ForceLawKind law) {
  switch (law) {
    case ForceLawKind::kLinearEdge:
      return "linear_edge";
    case ForceLawKind::kKronenberg:
      return "kronenberg";
    case ForceLawKind::kPowerLaw:
      break;
  }
  return "power_law";
}

std::string to_string(RunoutHelix helix) {
  return helix == RunoutHelix::kTipPattern ? "tip_pattern" : "rigid_axis";
}

EngagedArc engaged_arc(const ModelConfig& c) {
  const double radius_um = tool_radius_um(c);
  const double side_rad = std::acos((radius_um - 1e3 * c.process.radial_depth_mm) / radius_um);
  EngagedArc arc{0.0, std::numbers::pi};
  if (c.process.operation == Operation::kUpMilling) {
    arc.to_rad = side_rad;
  } else if (c.process.operation == Operation::kDownMilling) {
    arc.from_rad = std::numbers::pi - side_rad;
  }
  return arc;
}

double helix_lag_total_rad(const ModelConfig& c) {
  if (!c.effects.helix_lag.enabled) {
    return 0.0;
  }
  const double radius_mm = c.tool.diameter_mm / 2.0;
  const double t = c.process.axial_depth_mm * std::tan(c.tool.helix_deg * std::numbers::pi / 180.0);
  const double cos_beta = (2.0 * radius_mm * radius_mm - t * t) / (2.0 * radius_mm * radius_mm);
  return std::acos(std::clamp(cos_beta, -1.0, 1.0));
}

void runout_disc_angles_rad(const ModelConfig& c, std::vector<double>& out) {
  const auto& e = c.effects;
  if (!e.runout.enabled || e.runout.helix != RunoutHelix::kRigidAxis || !e.helix_lag.enabled) {
    out.clear();
    return;
  }
  const double beta = helix_lag_total_rad(c);
  const int discs = e.helix_lag.discs;
  out.resize(static_cast<std::size_t>(discs));
  for (int i = 0; i < discs; ++i) {
    out[static_cast<std::size_t>(i)] = (i + 0.5) * beta / discs;
  }
}

void flute_pitch_angles_rad(const Tool& tool, std::vector<double>& psi) {
  psi.resize(static_cast<std::size_t>(tool.flutes));
  psi[0] = 0.0;
  for (int j = 1; j < tool.flutes; ++j) {
    const double step_deg = tool.pitch_deg.empty()
                                ? 360.0 / tool.flutes
                                : tool.pitch_deg[static_cast<std::size_t>(j - 1)];
    psi[static_cast<std::size_t>(j)] =
        psi[static_cast<std::size_t>(j - 1)] + step_deg * std::numbers::pi / 180.0;
  }
}

std::vector<double> flute_pitch_angles_rad(const Tool& tool) {
  std::vector<double> psi;
  flute_pitch_angles_rad(tool, psi);
  return psi;
}

void validate(const ModelConfig& c, const std::string& path) {
  const auto& tool = c.tool;
  if (!tool.pitch_deg.empty()) {
    if (static_cast<int>(tool.pitch_deg.size()) != tool.flutes) {
      config::fail(join(path, "tool.pitch_deg"), "has " + std::to_string(tool.pitch_deg.size()) +
                                                     " entries; needs one per flute (" +
                                                     std::to_string(tool.flutes) + ")");
    }
    double sum = 0.0;
    for (double p : tool.pitch_deg) {
      sum += p;
    }
    if (std::fabs(sum - 360.0) > 1e-6) {
      config::fail(join(path, "tool.pitch_deg"),
                   "entries sum to " + std::to_string(sum) + " deg; they must sum to 360");
    }
  }
  if (c.process.operation != Operation::kSlot && c.process.radial_depth_mm > tool.diameter_mm) {
    config::fail(join(path, "process.radial_depth_mm"),
                 "value " + std::to_string(c.process.radial_depth_mm) +
                     " exceeds the tool diameter " + std::to_string(tool.diameter_mm) + " mm");
  }
  const double radius_um = tool.diameter_mm * 500.0;
  if (c.effects.runout.enabled && c.effects.runout.offset_um >= 0.2 * radius_um) {
    config::fail(join(path, "effects.runout.offset_um"),
                 "value " + config::format_number(c.effects.runout.offset_um) +
                     " um must stay below a fifth of the tool radius (" +
                     config::format_number(0.2 * radius_um) + " um)");
  }
  if (c.process.feed_per_tooth_um >= 0.5 * radius_um) {
    config::fail(join(path, "process.feed_per_tooth_um"),
                 "value " + config::format_number(c.process.feed_per_tooth_um) +
                     " um must stay below half the tool radius (" +
                     config::format_number(0.5 * radius_um) + " um)");
  }
  if (c.effects.accumulation.enabled && !c.effects.min_chip.enabled) {
    config::fail(join(path, "effects.accumulation.enabled"),
                 "accumulation needs effects.min_chip.enabled (it uses h_min)");
  }
  const int steps = c.resolution.steps_per_rev;
  if (steps % tool.flutes != 0) {
    config::fail(join(path, "resolution.steps_per_rev"),
                 "value " + std::to_string(steps) + " must be a multiple of the flute count " +
                     std::to_string(tool.flutes));
  }
  if (c.effects.flank_wear.wear_um.size() != 1 &&
      static_cast<int>(c.effects.flank_wear.wear_um.size()) != tool.flutes) {
    config::fail(join(path, "effects.flank_wear.wear_um"),
                 "needs one value or one per flute (" + std::to_string(tool.flutes) + ")");
  }
}

ModelConfig model_config_from_json(const nlohmann::json& j, const std::string& path) {
  ObjectReader r(j, path);
  ModelConfig c;
  c.tool = read_tool(r.object("tool"));
  c.process = read_process(r.object("process"));
  c.material = read_material(r.object("material"));
  c.effects = read_effects(r.object("effects"), c.tool.flutes);
  {
    auto s = r.object("resolution");
    c.resolution.steps_per_rev = s.integer("steps_per_rev", c.resolution.steps_per_rev, 36, 36000);
    s.finish();
  }
  r.finish();
  validate(c, path);
  return c;
}

nlohmann::json to_json(const ModelConfig& c) {
  using nlohmann::json;
  const auto& pl = c.material.power_law;
  const auto& le = c.material.linear_edge;
  const auto& kr = c.material.kronenberg;
  const auto& e = c.effects;
  json tool = {{"diameter_mm", c.tool.diameter_mm},
               {"flutes", c.tool.flutes},
               {"helix_deg", c.tool.helix_deg},
               {"edge_radius_um", c.tool.edge_radius_um}};
  if (!c.tool.pitch_deg.empty()) {
    tool["pitch_deg"] = c.tool.pitch_deg;
  }
  return json{
      {"tool", tool},
      {"process",
       {{"operation", to_string(c.process.operation)},
        {"spindle_rpm", c.process.spindle_rpm},
        {"feed_per_tooth_um", c.process.feed_per_tooth_um},
        {"axial_depth_mm", c.process.axial_depth_mm},
        {"radial_depth_mm", c.process.radial_depth_mm}}},
      {"material",
       {{"name", c.material.name},
        {"law", to_string(c.material.law)},
        {"power_law",
         {{"k_tc_Nmm", pl.k_tc_Nmm},
          {"a_tc", pl.a_tc},
          {"k_nc_Nmm", pl.k_nc_Nmm},
          {"a_nc", pl.a_nc},
          {"k_tp_Nmm", pl.k_tp_Nmm},
          {"a_tp", pl.a_tp},
          {"k_np_Nmm", pl.k_np_Nmm},
          {"a_np", pl.a_np},
          {"k_ac_Nmm", pl.k_ac_Nmm},
          {"a_ac", pl.a_ac},
          {"k_ap_Nmm", pl.k_ap_Nmm},
          {"a_ap", pl.a_ap}}},
        {"linear_edge",
         {{"k_tc_N_per_mm2", le.k_tc_N_per_mm2},
          {"k_nc_N_per_mm2", le.k_nc_N_per_mm2},
          {"k_ac_N_per_mm2", le.k_ac_N_per_mm2},
          {"k_te_N_per_mm", le.k_te_N_per_mm},
          {"k_ne_N_per_mm", le.k_ne_N_per_mm},
          {"k_ae_N_per_mm", le.k_ae_N_per_mm},
          {"ploughing", le.ploughing_area ? "area" : "edge"},
          {"k_tp_N_per_mm3", le.k_tp_N_per_mm3},
          {"k_np_N_per_mm3", le.k_np_N_per_mm3},
          {"k_ap_N_per_mm3", le.k_ap_N_per_mm3},
          {"a_t_Nmm", le.a_t_Nmm},
          {"b_t", le.b_t},
          {"a_n_Nmm", le.a_n_Nmm},
          {"b_n", le.b_n},
          {"a_a_Nmm", le.a_a_Nmm},
          {"b_a", le.b_a}}},
        {"kronenberg",
         {{"k_s0_N_per_mm2", kr.k_s0_N_per_mm2},
          {"m", kr.m},
          {"radial_ratio", kr.radial_ratio},
          {"axial_ratio", kr.axial_ratio}}}}},
      {"effects",
       {{"runout",
         {{"enabled", e.runout.enabled},
          {"offset_um", e.runout.offset_um},
          {"angle_rad", e.runout.angle_rad},
          {"helix", to_string(e.runout.helix)}}},
        {"trochoidal", {{"enabled", e.trochoidal.enabled}}},
        {"multi_pass", {{"enabled", e.multi_pass.enabled}, {"passes", e.multi_pass.passes}}},
        {"min_chip", {{"enabled", e.min_chip.enabled}, {"h_min_um", e.min_chip.h_min_um}}},
        {"accumulation", {{"enabled", e.accumulation.enabled}}},
        {"deflection",
         {{"enabled", e.deflection.enabled},
          {"stiffness_N_per_um", e.deflection.stiffness_N_per_um}}},
        {"helix_lag", {{"enabled", e.helix_lag.enabled}, {"discs", e.helix_lag.discs}}},
        {"flank_wear",
         {{"enabled", e.flank_wear.enabled},
          {"wear_um", e.flank_wear.wear_um},
          {"k_wt_N_per_mm2", e.flank_wear.k_wt_N_per_mm2},
          {"k_wn_N_per_mm2", e.flank_wear.k_wn_N_per_mm2}}},
        {"dynamometer",
         {{"enabled", e.dynamometer.enabled},
          {"natural_hz", e.dynamometer.natural_hz},
          {"damping_ratio", e.dynamometer.damping_ratio}}}}},
      {"resolution", {{"steps_per_rev", c.resolution.steps_per_rev}}}};
}

void set_effect(ModelConfig& c, const std::string& name, bool on) {
  auto& e = c.effects;
  if (name == "runout") {
    e.runout.enabled = on;
  } else if (name == "trochoidal") {
    e.trochoidal.enabled = on;
  } else if (name == "multi_pass") {
    e.multi_pass.enabled = on;
  } else if (name == "min_chip") {
    e.min_chip.enabled = on;
    if (!on) {
      e.accumulation.enabled = false;
    }
  } else if (name == "accumulation") {
    e.accumulation.enabled = on;
    if (on) {
      e.min_chip.enabled = true;
    }
  } else if (name == "deflection") {
    e.deflection.enabled = on;
  } else if (name == "helix_lag") {
    e.helix_lag.enabled = on;
  } else if (name == "flank_wear") {
    e.flank_wear.enabled = on;
  } else if (name == "dynamometer") {
    e.dynamometer.enabled = on;
  } else if (name == "ploughing_area") {
    c.material.linear_edge.ploughing_area = on;
  } else {
    throw std::invalid_argument("unknown effect \"" + name + "\"");
  }
}

bool effect_enabled(const ModelConfig& c, const std::string& name) {
  const auto& e = c.effects;
  if (name == "runout") {
    return e.runout.enabled;
  }
  if (name == "trochoidal") {
    return e.trochoidal.enabled;
  }
  if (name == "multi_pass") {
    return e.multi_pass.enabled;
  }
  if (name == "min_chip") {
    return e.min_chip.enabled;
  }
  if (name == "accumulation") {
    return e.accumulation.enabled;
  }
  if (name == "deflection") {
    return e.deflection.enabled;
  }
  if (name == "helix_lag") {
    return e.helix_lag.enabled;
  }
  if (name == "flank_wear") {
    return e.flank_wear.enabled;
  }
  if (name == "dynamometer") {
    return e.dynamometer.enabled;
  }
  if (name == "ploughing_area") {
    return c.material.linear_edge.ploughing_area;
  }
  throw std::invalid_argument("unknown effect \"" + name + "\"");
}

ModelConfig without_effects(ModelConfig c) {
  for (const char* name : kEffectNames) {
    set_effect(c, name, false);
  }
  return c;
}

int passes_to_look_back(const ModelConfig& c) {
  constexpr int kMaxAutoPasses = 32;
  constexpr double kPi = std::numbers::pi;
  const int flutes = c.tool.flutes;
  if (!c.effects.multi_pass.enabled) {
    return 1;
  }
  if (c.effects.multi_pass.passes > 0) {
    return c.effects.multi_pass.passes;
  }
  int passes = flutes;
  if (c.effects.accumulation.enabled && c.effects.min_chip.h_min_um > 0.0) {
    const double per_pass_um = c.process.feed_per_tooth_um * std::sin(2.0 * kPi / 180.0);
    const double extra = std::ceil(c.effects.min_chip.h_min_um / per_pass_um);
    passes = static_cast<int>(std::min<double>(kMaxAutoPasses, flutes * (1.0 + extra)));
  }
  return std::max(passes, flutes);
}

}  // namespace millwatch::model
