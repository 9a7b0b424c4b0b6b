#include "core/signal/daq_scaling.hpp"

#include <cmath>

#include "core/config/json_reader.hpp"

namespace millwatch::signal {

DaqChannelScaling::Sample DaqChannelScaling::scale(std::uint32_t code) const {
  const double volts = volts_min + static_cast<double>(code) * (volts_max - volts_min) /
                                       static_cast<double>(maxdata);
  const bool daq_clipped = code == 0 || code >= maxdata;
  const bool amplifier_overload = std::fabs(volts) >= full_scale_V;
  if (daq_clipped || amplifier_overload) {
    return {std::copysign(range_N, volts), true};
  }
  return {volts * range_N / full_scale_V, false};
}

DaqChannelScaling daq_channel_from_json(const nlohmann::json& j, const std::string& path) {
  config::ObjectReader r(j, path);
  DaqChannelScaling c;
  c.daq_channel = r.integer("daq_channel", c.daq_channel, 0, 255);
  c.volts_min = r.number("volts_min", c.volts_min, config::closed(-100.0, 0.0, "V"));
  c.volts_max = r.number("volts_max", c.volts_max, config::positive(100.0, "V"));
  c.maxdata = static_cast<std::uint32_t>(r.integer64("maxdata", c.maxdata, 1, 4294967295LL));
  c.range_N = r.number("range_N", c.range_N, config::positive(1e6, "N"));
  c.full_scale_V = r.number("full_scale_V", c.full_scale_V, config::positive(100.0, "V"));
  r.finish();
  return c;
}

}  // namespace millwatch::signal
