#include "core/model/parameter_map.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <stdexcept>

namespace millwatch::model {
namespace {

constexpr double kBig = 1e7;    // the configuration's limit on force coefficients
constexpr double kTiny = 1e-3;  // the smallest value offered for a quantity that must be > 0
constexpr double kTwoPi = 2.0 * std::numbers::pi;

/// A catalogue entry; `law` empty means every law.
struct Entry {
  ParameterId id;
  const char* name;
  const char* field;
  const char* effect;
  std::optional<ForceLawKind> law;
  double scale, lower, upper;
};

// Bounds as model_config.cpp reads them (k: [0, 1e7]; exponents: (0, 2]; linear K: ±1e7; ...).
const Entry kCatalogue[] = {
    {ParameterId::kRho, "rho_um", "effects.runout.offset_um", "runout", {}, 1.0, 0.0, 0.0},
    {ParameterId::kGamma,
     "gamma_rad",
     "effects.runout.angle_rad",
     "runout",
     {},
     1.0,
     -kTwoPi,
     kTwoPi},
    {ParameterId::kPowerKtc, "k_tc_Nmm", "material.power_law.k_tc_Nmm", "force_law",
     ForceLawKind::kPowerLaw, 500.0, 0.0, kBig},
    {ParameterId::kPowerAtc, "a_tc", "material.power_law.a_tc", "force_law",
     ForceLawKind::kPowerLaw, 0.5, kTiny, 2.0},
    {ParameterId::kPowerKnc, "k_nc_Nmm", "material.power_law.k_nc_Nmm", "force_law",
     ForceLawKind::kPowerLaw, 100.0, 0.0, kBig},
    {ParameterId::kPowerAnc, "a_nc", "material.power_law.a_nc", "force_law",
     ForceLawKind::kPowerLaw, 0.5, kTiny, 2.0},
    {ParameterId::kPowerKac, "k_ac_Nmm", "material.power_law.k_ac_Nmm", "force_law",
     ForceLawKind::kPowerLaw, 100.0, 0.0, kBig},
    {ParameterId::kPowerAac, "a_ac", "material.power_law.a_ac", "force_law",
     ForceLawKind::kPowerLaw, 0.5, kTiny, 2.0},
    {ParameterId::kLinearKtc, "k_tc_N_per_mm2", "material.linear_edge.k_tc_N_per_mm2", "force_law",
     ForceLawKind::kLinearEdge, 1000.0, -kBig, kBig},
    {ParameterId::kLinearKnc, "k_nc_N_per_mm2", "material.linear_edge.k_nc_N_per_mm2", "force_law",
     ForceLawKind::kLinearEdge, 500.0, -kBig, kBig},
    {ParameterId::kLinearKac, "k_ac_N_per_mm2", "material.linear_edge.k_ac_N_per_mm2", "force_law",
     ForceLawKind::kLinearEdge, 100.0, -kBig, kBig},
    {ParameterId::kLinearKte, "k_te_N_per_mm", "material.linear_edge.k_te_N_per_mm", "force_law",
     ForceLawKind::kLinearEdge, 10.0, -kBig, kBig},
    {ParameterId::kLinearKne, "k_ne_N_per_mm", "material.linear_edge.k_ne_N_per_mm", "force_law",
     ForceLawKind::kLinearEdge, 10.0, -kBig, kBig},
    {ParameterId::kLinearKae, "k_ae_N_per_mm", "material.linear_edge.k_ae_N_per_mm", "force_law",
     ForceLawKind::kLinearEdge, 1.0, -kBig, kBig},
    {ParameterId::kKronenbergKs0, "k_s0_N_per_mm2", "material.kronenberg.k_s0_N_per_mm2",
     "force_law", ForceLawKind::kKronenberg, 1000.0, kTiny, kBig},
    {ParameterId::kKronenbergM, "m", "material.kronenberg.m", "force_law",
     ForceLawKind::kKronenberg, 4.0, 1.0 + kTiny, 100.0},
    {ParameterId::kKronenbergRadial, "radial_ratio", "material.kronenberg.radial_ratio",
     "force_law", ForceLawKind::kKronenberg, 0.5, 0.0, 10.0},
    {ParameterId::kKronenbergAxial, "axial_ratio", "material.kronenberg.axial_ratio", "force_law",
     ForceLawKind::kKronenberg, 0.1, -10.0, 10.0},
    {ParameterId::kHmin, "h_min_um", "effects.min_chip.h_min_um", "min_chip", {}, 0.5, 0.0, 50.0},
    {ParameterId::kPowerKtp, "k_tp_Nmm", "material.power_law.k_tp_Nmm", "min_chip",
     ForceLawKind::kPowerLaw, 500.0, 0.0, kBig},
    {ParameterId::kPowerAtp, "a_tp", "material.power_law.a_tp", "min_chip", ForceLawKind::kPowerLaw,
     0.5, kTiny, 2.0},
    {ParameterId::kPowerKnp, "k_np_Nmm", "material.power_law.k_np_Nmm", "min_chip",
     ForceLawKind::kPowerLaw, 100.0, 0.0, kBig},
    {ParameterId::kPowerAnp, "a_np", "material.power_law.a_np", "min_chip", ForceLawKind::kPowerLaw,
     0.5, kTiny, 2.0},
    {ParameterId::kPowerKap, "k_ap_Nmm", "material.power_law.k_ap_Nmm", "min_chip",
     ForceLawKind::kPowerLaw, 100.0, 0.0, kBig},
    {ParameterId::kPowerAap, "a_ap", "material.power_law.a_ap", "min_chip", ForceLawKind::kPowerLaw,
     0.5, kTiny, 2.0},
    {ParameterId::kLinearAt, "a_t_Nmm", "material.linear_edge.a_t_Nmm", "min_chip",
     ForceLawKind::kLinearEdge, 100.0, 0.0, kBig},
    {ParameterId::kLinearBt, "b_t", "material.linear_edge.b_t", "min_chip",
     ForceLawKind::kLinearEdge, 0.5, kTiny, 2.0},
    {ParameterId::kLinearAn, "a_n_Nmm", "material.linear_edge.a_n_Nmm", "min_chip",
     ForceLawKind::kLinearEdge, 100.0, 0.0, kBig},
    {ParameterId::kLinearBn, "b_n", "material.linear_edge.b_n", "min_chip",
     ForceLawKind::kLinearEdge, 0.5, kTiny, 2.0},
    {ParameterId::kLinearAa, "a_a_Nmm", "material.linear_edge.a_a_Nmm", "min_chip",
     ForceLawKind::kLinearEdge, 100.0, 0.0, kBig},
    {ParameterId::kLinearBa, "b_a", "material.linear_edge.b_a", "min_chip",
     ForceLawKind::kLinearEdge, 0.5, kTiny, 2.0},
    {ParameterId::kLinearKtp, "k_tp_N_per_mm3", "material.linear_edge.k_tp_N_per_mm3",
     "ploughing_area", ForceLawKind::kLinearEdge, 5000.0, 0.0, 1e9},
    {ParameterId::kLinearKnp, "k_np_N_per_mm3", "material.linear_edge.k_np_N_per_mm3",
     "ploughing_area", ForceLawKind::kLinearEdge, 5000.0, 0.0, 1e9},
    {ParameterId::kLinearKap, "k_ap_N_per_mm3", "material.linear_edge.k_ap_N_per_mm3",
     "ploughing_area", ForceLawKind::kLinearEdge, 500.0, 0.0, 1e9},
    {ParameterId::kStiffness,
     "stiffness_N_per_um",
     "effects.deflection.stiffness_N_per_um",
     "deflection",
     {},
     0.5,
     kTiny,
     1e6},
    {ParameterId::kWear,
     "wear_um",
     "effects.flank_wear.wear_um[0]",
     "flank_wear",
     {},
     10.0,
     0.0,
     2000.0},
    {ParameterId::kWearFlute,
     "wear_um[",
     "effects.flank_wear.wear_um[",
     "flank_wear",
     {},
     10.0,
     0.0,
     2000.0},
    {ParameterId::kWearKt,
     "k_wt_N_per_mm2",
     "effects.flank_wear.k_wt_N_per_mm2",
     "flank_wear",
     {},
     300.0,
     0.0,
     kBig},
    {ParameterId::kWearKn,
     "k_wn_N_per_mm2",
     "effects.flank_wear.k_wn_N_per_mm2",
     "flank_wear",
     {},
     600.0,
     0.0,
     kBig},
    {ParameterId::kNaturalX,
     "natural_hz_x",
     "effects.dynamometer.natural_hz[0]",
     "dynamometer",
     {},
     2000.0,
     1.0,
     1e6},
    {ParameterId::kNaturalY,
     "natural_hz_y",
     "effects.dynamometer.natural_hz[1]",
     "dynamometer",
     {},
     2000.0,
     1.0,
     1e6},
    {ParameterId::kNaturalZ,
     "natural_hz_z",
     "effects.dynamometer.natural_hz[2]",
     "dynamometer",
     {},
     2000.0,
     1.0,
     1e6},
    {ParameterId::kDampingX,
     "damping_ratio_x",
     "effects.dynamometer.damping_ratio[0]",
     "dynamometer",
     {},
     0.05,
     1e-4,
     5.0},
    {ParameterId::kDampingY,
     "damping_ratio_y",
     "effects.dynamometer.damping_ratio[1]",
     "dynamometer",
     {},
     0.05,
     1e-4,
     5.0},
    {ParameterId::kDampingZ,
     "damping_ratio_z",
     "effects.dynamometer.damping_ratio[2]",
     "dynamometer",
     {},
     0.05,
     1e-4,
     5.0},
};

/// The effects with parameters, in the order available_parameters lists them.
const char* const kParameterEffects[] = {"runout",     "force_law",  "min_chip",   "ploughing_area",
                                         "deflection", "flank_wear", "dynamometer"};

ParameterInfo info_of(const Entry& e, const ModelConfig& config, int flute = -1) {
  ParameterInfo p;
  p.id = e.id;
  p.flute = flute;
  p.name = e.name;
  p.field = e.field;
  if (flute >= 0) {
    p.name += std::to_string(flute) + "]";
    p.field += std::to_string(flute) + "]";
  }
  p.effect = e.effect;
  p.scale = e.scale;
  p.lower = e.lower;
  p.upper = e.upper;
  if (e.id == ParameterId::kRho) {
    // validate(): ρ < R/5 (the model's small-runout geometry).
    p.upper = std::nextafter(0.2 * tool_radius_um(config), 0.0);
  }
  return p;
}

bool applies(const Entry& e, const ModelConfig& config) {
  return !e.law || *e.law == config.material.law;
}

void append_available(const Entry& e, const ModelConfig& config, std::vector<ParameterInfo>& out) {
  if (!applies(e, config)) {
    return;
  }
  const std::size_t wear_values = config.effects.flank_wear.wear_um.size();
  if (e.id == ParameterId::kWear) {
    if (wear_values == 1) {
      out.push_back(info_of(e, config));
    }
    return;
  }
  if (e.id == ParameterId::kWearFlute) {
    if (wear_values != 1) {
      for (std::size_t j = 0; j < wear_values; ++j) {
        out.push_back(info_of(e, config, static_cast<int>(j)));
      }
    }
    return;
  }
  out.push_back(info_of(e, config));
}

/// The field of parameter p (const or not, as the configuration).
template <class Config>
auto field_of(Config& c, const ParameterInfo& p) -> decltype((c.effects.runout.offset_um)) {
  auto& pl = c.material.power_law;
  auto& le = c.material.linear_edge;
  auto& kr = c.material.kronenberg;
  auto& e = c.effects;
  switch (p.id) {
    case ParameterId::kRho:
      return e.runout.offset_um;
    case ParameterId::kGamma:
      return e.runout.angle_rad;
    case ParameterId::kPowerKtc:
      return pl.k_tc_Nmm;
    case ParameterId::kPowerAtc:
      return pl.a_tc;
    case ParameterId::kPowerKnc:
      return pl.k_nc_Nmm;
    case ParameterId::kPowerAnc:
      return pl.a_nc;
    case ParameterId::kPowerKac:
      return pl.k_ac_Nmm;
    case ParameterId::kPowerAac:
      return pl.a_ac;
    case ParameterId::kPowerKtp:
      return pl.k_tp_Nmm;
    case ParameterId::kPowerAtp:
      return pl.a_tp;
    case ParameterId::kPowerKnp:
      return pl.k_np_Nmm;
    case ParameterId::kPowerAnp:
      return pl.a_np;
    case ParameterId::kPowerKap:
      return pl.k_ap_Nmm;
    case ParameterId::kPowerAap:
      return pl.a_ap;
    case ParameterId::kLinearKtc:
      return le.k_tc_N_per_mm2;
    case ParameterId::kLinearKnc:
      return le.k_nc_N_per_mm2;
    case ParameterId::kLinearKac:
      return le.k_ac_N_per_mm2;
    case ParameterId::kLinearKte:
      return le.k_te_N_per_mm;
    case ParameterId::kLinearKne:
      return le.k_ne_N_per_mm;
    case ParameterId::kLinearKae:
      return le.k_ae_N_per_mm;
    case ParameterId::kLinearKtp:
      return le.k_tp_N_per_mm3;
    case ParameterId::kLinearKnp:
      return le.k_np_N_per_mm3;
    case ParameterId::kLinearKap:
      return le.k_ap_N_per_mm3;
    case ParameterId::kLinearAt:
      return le.a_t_Nmm;
    case ParameterId::kLinearBt:
      return le.b_t;
    case ParameterId::kLinearAn:
      return le.a_n_Nmm;
    case ParameterId::kLinearBn:
      return le.b_n;
    case ParameterId::kLinearAa:
      return le.a_a_Nmm;
    case ParameterId::kLinearBa:
      return le.b_a;
    case ParameterId::kKronenbergKs0:
      return kr.k_s0_N_per_mm2;
    case ParameterId::kKronenbergM:
      return kr.m;
    case ParameterId::kKronenbergRadial:
      return kr.radial_ratio;
    case ParameterId::kKronenbergAxial:
      return kr.axial_ratio;
    case ParameterId::kHmin:
      return e.min_chip.h_min_um;
    case ParameterId::kStiffness:
      return e.deflection.stiffness_N_per_um;
    case ParameterId::kWear:
    case ParameterId::kWearFlute: {
      const auto j = static_cast<std::size_t>(std::max(p.flute, 0));
      if (j >= e.flank_wear.wear_um.size()) {
        throw std::invalid_argument("parameter " + p.name + ": the configuration has " +
                                    std::to_string(e.flank_wear.wear_um.size()) + " wear value(s)");
      }
      return e.flank_wear.wear_um[j];
    }
    case ParameterId::kWearKt:
      return e.flank_wear.k_wt_N_per_mm2;
    case ParameterId::kWearKn:
      return e.flank_wear.k_wn_N_per_mm2;
    case ParameterId::kNaturalX:
      return e.dynamometer.natural_hz[0];
    case ParameterId::kNaturalY:
      return e.dynamometer.natural_hz[1];
    case ParameterId::kNaturalZ:
      return e.dynamometer.natural_hz[2];
    case ParameterId::kDampingX:
      return e.dynamometer.damping_ratio[0];
    case ParameterId::kDampingY:
      return e.dynamometer.damping_ratio[1];
    case ParameterId::kDampingZ:
      return e.dynamometer.damping_ratio[2];
  }
  throw std::logic_error("parameter_map: unhandled parameter " + p.name);
}

void check_size(const ParameterMap& map, Eigen::Index size) {
  if (size != map.size()) {
    throw std::invalid_argument("parameter vector has " + std::to_string(size) +
                                " elements; the map has " + std::to_string(map.size()));
  }
}

}  // namespace

std::vector<ParameterInfo> available_parameters(const ModelConfig& config) {
  std::vector<ParameterInfo> out;
  for (const char* effect : kParameterEffects) {
    for (const Entry& e : kCatalogue) {
      if (std::string_view(e.effect) == effect) {
        append_available(e, config, out);
      }
    }
  }
  return out;
}

std::vector<std::string> parameters_of_effect(const ModelConfig& config, std::string_view effect) {
  const bool known = effect == "force_law" || std::find(kEffectNames.begin(), kEffectNames.end(),
                                                        effect) != kEffectNames.end();
  if (!known) {
    std::string list = "force_law";
    for (const char* e : kEffectNames) {
      list += std::string(", ") + e;
    }
    throw std::invalid_argument("unknown effect \"" + std::string(effect) + "\" (known: " + list +
                                ")");
  }
  std::vector<std::string> names;
  for (const ParameterInfo& p : available_parameters(config)) {
    if (p.effect == effect) {
      names.push_back(p.name);
    }
  }
  return names;
}

ParameterMap make_parameter_map(const ModelConfig& config, std::span<const std::string> names) {
  const std::vector<ParameterInfo> available = available_parameters(config);
  ParameterMap map;
  for (const std::string& name : names) {
    const auto it = std::find_if(available.begin(), available.end(),
                                 [&](const ParameterInfo& p) { return p.name == name; });
    if (it == available.end()) {
      std::string list;
      for (const ParameterInfo& p : available) {
        list += (list.empty() ? "" : ", ") + p.name;
      }
      throw std::invalid_argument("unknown parameter \"" + name + "\" for this configuration (" +
                                  to_string(config.material.law) + " law, " +
                                  std::to_string(config.effects.flank_wear.wear_um.size()) +
                                  " wear value(s)); known: " + list);
    }
    for (const ParameterInfo& p : map.parameters) {
      if (p.name == name) {
        throw std::invalid_argument("parameter \"" + name + "\" is named twice");
      }
    }
    map.parameters.push_back(*it);
  }
  return map;
}

ParameterMap make_effect_parameter_map(const ModelConfig& config,
                                       std::span<const std::string> effects) {
  std::vector<std::string> names;
  for (const std::string& effect : effects) {
    for (std::string& n : parameters_of_effect(config, effect)) {
      names.push_back(std::move(n));
    }
  }
  return make_parameter_map(config, names);
}

void get_parameters(const ParameterMap& map, const ModelConfig& config,
                    Eigen::Ref<Eigen::VectorXd> x) {
  check_size(map, x.size());
  for (int i = 0; i < map.size(); ++i) {
    x[i] = field_of(config, map.parameters[static_cast<std::size_t>(i)]);
  }
}

Eigen::VectorXd get_parameters(const ParameterMap& map, const ModelConfig& config) {
  Eigen::VectorXd x(map.size());
  get_parameters(map, config, x);
  return x;
}

void set_parameters(const ParameterMap& map, const Eigen::Ref<const Eigen::VectorXd>& x,
                    ModelConfig& config) {
  check_size(map, x.size());
  for (int i = 0; i < map.size(); ++i) {
    field_of(config, map.parameters[static_cast<std::size_t>(i)]) = x[i];
  }
}

Eigen::VectorXd parameter_scales(const ParameterMap& map) {
  Eigen::VectorXd v(map.size());
  for (int i = 0; i < map.size(); ++i) {
    v[i] = map.parameters[static_cast<std::size_t>(i)].scale;
  }
  return v;
}

Eigen::VectorXd lower_bounds(const ParameterMap& map) {
  Eigen::VectorXd v(map.size());
  for (int i = 0; i < map.size(); ++i) {
    v[i] = map.parameters[static_cast<std::size_t>(i)].lower;
  }
  return v;
}

Eigen::VectorXd upper_bounds(const ParameterMap& map) {
  Eigen::VectorXd v(map.size());
  for (int i = 0; i < map.size(); ++i) {
    v[i] = map.parameters[static_cast<std::size_t>(i)].upper;
  }
  return v;
}

bool within_bounds(const ParameterMap& map, const Eigen::Ref<const Eigen::VectorXd>& x) {
  check_size(map, x.size());
  for (int i = 0; i < map.size(); ++i) {
    const auto& p = map.parameters[static_cast<std::size_t>(i)];
    if (!(x[i] >= p.lower && x[i] <= p.upper)) {
      return false;
    }
  }
  return true;
}

}  // namespace millwatch::model
