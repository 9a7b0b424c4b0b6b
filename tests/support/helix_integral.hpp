#pragma once
// The closed form a helix-lag model must converge to, for tests: two flutes without runout, the
// linear law without edge terms (h = f_t·sin θ, F_t = K_tc·h, F_r = K_nc·h per unit length), the
// lag uniform over [0, β] along the depth ([000] eqs 2-4, 6, 8). The discs of the model are a
// midpoint rule of this integral, converging as 1/K².

#include "core/model/model_config.hpp"

namespace millwatch::test {

/// Fx (N) at spindle angle `phi_rad` of the cut `c` (its helix, depth, diameter, feed and linear
/// cutting coefficients; the edge coefficients are taken as zero).
double helix_integral_fx_N(const model::ModelConfig& c, double phi_rad);

}  // namespace millwatch::test
