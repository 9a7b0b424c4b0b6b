#pragma once
// A DAQ board's scan timing against the monitor's sample rate. A board times its scans in whole
// nanoseconds (Comedi's scan_begin_arg, or convert_arg per channel): 333,300 Hz is 3,000.3 ns,
// which a board can only round — to 3,000 ns, 333,333.3 Hz. Blocks stamped at the configured
// rate would then put every speed and period 0.01 % off, stated as fact. So the daemon asks for
// the nearest period, reads back what the board took, and refuses to start on a rate it cannot
// keep, naming the one it can.

#include <cstdint>
#include <string>

namespace millwatch::daemon {

/// The whole-nanosecond scan period nearest to `sample_rate_hz` (> 0).
[[nodiscard]] std::uint32_t scan_period_ns(double sample_rate_hz);

/// Empty when a scan every `period_ns` keeps `sample_rate_hz` to 1e-6 (a speed 0.025 rpm off at
/// 25,000 rpm); else why not, with the rate the board gives and the setting that matches it.
[[nodiscard]] std::string scan_rate_mismatch(double sample_rate_hz, std::uint64_t period_ns);

}  // namespace millwatch::daemon
