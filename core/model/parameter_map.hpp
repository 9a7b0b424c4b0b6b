#pragma once
// Named free parameters of the model ↔ ModelConfig fields, for identification (a fitter moves a
// parameter vector) and diagnosis (effects, and their parameters, switched on one at a time).
//
// Each parameter has a name (units in the name), the configuration field it is (its JSON path,
// model_config.hpp), the effect it belongs to (one of kEffectNames, or "force_law" for the
// coefficients every cut has), a typical scale and bounds:
//
//   runout        rho_um [0, R/5)   gamma_rad [−2π, 2π]                        ([000] eq 9)
//   force_law     power law:  k_tc_Nmm a_tc k_nc_Nmm a_nc k_ac_Nmm a_ac          ([000] eq 5)
//                 linear edge: k_tc_N_per_mm2 k_nc_N_per_mm2 k_ac_N_per_mm2
//                              k_te_N_per_mm k_ne_N_per_mm k_ae_N_per_mm        ([002] eq 18)
//                 Kronenberg: k_s0_N_per_mm2 m radial_ratio axial_ratio        ([003] eqs 7-8)
//   min_chip      h_min_um; power law: k_tp_Nmm a_tp k_np_Nmm a_np k_ap_Nmm a_ap (ploughing
//                 regime, [000] eq 5); linear edge: a_t_Nmm b_t a_n_Nmm b_n a_a_Nmm b_a
//                 ([002] eq 17)
//   ploughing_area k_tp_N_per_mm3 k_np_N_per_mm3 k_ap_N_per_mm3 (linear edge, [001] eqs 18-21)
//   deflection    stiffness_N_per_um (k_n, [000] eqs 21-24)
//   flank_wear    wear_um (all flutes, when the configuration has one value) or wear_um[j]
//                 (flute j, when it has one per flute), k_wt_N_per_mm2, k_wn_N_per_mm2
//   dynamometer   natural_hz_x/_y/_z, damping_ratio_x/_y/_z
// The force law's parameters exist only for the law the configuration uses. Bounds are the
// configuration's own limits (model_config_from_json and validate accept every value inside
// them); an open end (a value that must stay > 0) is given as a small positive number. Scales
// are typical magnitudes of [000]-[003]'s values, for scaling a fitter's steps.
//
// Plain structs and free functions; set_parameters()/get_parameters() allocate nothing.

#include <Eigen/Core>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/model/model_config.hpp"

namespace millwatch::model {

/// Which configuration field a parameter is (internal identity; use the names).
enum class ParameterId {
  kRho,
  kGamma,
  kPowerKtc,
  kPowerAtc,
  kPowerKnc,
  kPowerAnc,
  kPowerKac,
  kPowerAac,
  kPowerKtp,
  kPowerAtp,
  kPowerKnp,
  kPowerAnp,
  kPowerKap,
  kPowerAap,
  kLinearKtc,
  kLinearKnc,
  kLinearKac,
  kLinearKte,
  kLinearKne,
  kLinearKae,
  kLinearKtp,
  kLinearKnp,
  kLinearKap,
  kLinearAt,
  kLinearBt,
  kLinearAn,
  kLinearBn,
  kLinearAa,
  kLinearBa,
  kKronenbergKs0,
  kKronenbergM,
  kKronenbergRadial,
  kKronenbergAxial,
  kHmin,
  kStiffness,
  kWear,
  kWearFlute,
  kWearKt,
  kWearKn,
  kNaturalX,
  kNaturalY,
  kNaturalZ,
  kDampingX,
  kDampingY,
  kDampingZ,
};

/// One free parameter.
struct ParameterInfo {
  ParameterId id = ParameterId::kRho;
  int flute = -1;      ///< for wear_um[j]: j; otherwise −1
  std::string name;    ///< e.g. "rho_um", "wear_um[1]"
  std::string field;   ///< configuration path, e.g. "effects.runout.offset_um"
  std::string effect;  ///< one of kEffectNames, or "force_law"
  double scale = 1.0;  ///< typical magnitude (units of the parameter)
  double lower = 0.0;  ///< smallest allowed value
  double upper = 0.0;  ///< largest allowed value
};

/// An ordered selection of parameters: element i of a parameter vector is parameters[i].
struct ParameterMap {
  std::vector<ParameterInfo> parameters;
  [[nodiscard]] int size() const { return static_cast<int>(parameters.size()); }
};

/// Every parameter that exists for `config` (its force law, its flute count and wear layout),
/// whether its effect is on or not, in the order of the file comment.
std::vector<ParameterInfo> available_parameters(const ModelConfig& config);

/// The parameters of one effect (one of kEffectNames or "force_law") for `config`, e.g.
/// {"rho_um", "gamma_rad"} for "runout"; empty for an effect without parameters.
/// @throws std::invalid_argument for an unknown effect name
std::vector<std::string> parameters_of_effect(const ModelConfig& config, std::string_view effect);

/// The map of the named parameters, in that order.
/// @throws std::invalid_argument naming the first name that does not exist for `config` (an
///         unknown name, another law's coefficient, a wear entry the configuration does not
///         have) and listing the ones that do, or a name given twice
ParameterMap make_parameter_map(const ModelConfig& config, std::span<const std::string> names);
/// All parameters of the named effects, in the order of the effects given.
ParameterMap make_effect_parameter_map(const ModelConfig& config,
                                       std::span<const std::string> effects);

/// x[i] = the configuration's value of parameter i. x.size() must be map.size().
void get_parameters(const ParameterMap& map, const ModelConfig& config,
                    Eigen::Ref<Eigen::VectorXd> x);
[[nodiscard]] Eigen::VectorXd get_parameters(const ParameterMap& map, const ModelConfig& config);

/// Writes x[i] into parameter i's field (no clamping: see within_bounds). Allocates nothing.
/// @throws std::invalid_argument if x.size() ≠ map.size(), or a wear entry is missing
void set_parameters(const ParameterMap& map, const Eigen::Ref<const Eigen::VectorXd>& x,
                    ModelConfig& config);

/// Per-parameter scale, lower and upper bounds, as vectors in map order.
[[nodiscard]] Eigen::VectorXd parameter_scales(const ParameterMap& map);
[[nodiscard]] Eigen::VectorXd lower_bounds(const ParameterMap& map);
[[nodiscard]] Eigen::VectorXd upper_bounds(const ParameterMap& map);
/// Whether lower ≤ x ≤ upper element-wise.
[[nodiscard]] bool within_bounds(const ParameterMap& map,
                                 const Eigen::Ref<const Eigen::VectorXd>& x);

}  // namespace millwatch::model
