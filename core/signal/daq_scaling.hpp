#pragma once
// From a DAQ's raw codes to newtons, for a channel wired to a charge amplifier.
//
//   volts  = volts_min + code·(volts_max − volts_min)/maxdata      (the DAQ's range)
//   newton = volts · range_N / full_scale_V                        (the amplifier's setting:
//            a Kistler 5015 puts ±full_scale_V out for ±range_N in)
// A sample is saturated when the DAQ clipped it (code at 0 or maxdata) or the amplifier did
// (|volts| at its full scale): it is then reported as ±range_N with the flag set, so that the
// pipeline's saturation check (saturation_N = range_N) counts it.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

namespace millwatch::signal {

struct DaqChannelScaling {
  int daq_channel = 0;       ///< the DAQ's analogue input
  double volts_min = -10.0;  ///< DAQ range
  double volts_max = 10.0;
  std::uint32_t maxdata = 65535;  ///< largest raw code
  double range_N = 100.0;         ///< charge amplifier measuring range (full scale), N
  double full_scale_V = 10.0;     ///< amplifier output at full scale, V

  struct Sample {
    double force_N = 0.0;
    bool saturated = false;
  };
  [[nodiscard]] Sample scale(std::uint32_t code) const;
};

/// @throws config::ConfigError naming the field.
DaqChannelScaling daq_channel_from_json(const nlohmann::json& j, const std::string& path);

}  // namespace millwatch::signal
