#pragma once
// The daemon's configuration file (JSON), validated at load:
//   { "monitor": { MonitorConfig },
//     "source": { "kind": "lcm", "channel": "MILLWATCH_FORCE_RAW", "max_block_samples": 4096,
//                 "wake_period_s": 0.005, "receive": "batched" }
//            or { "kind": "comedi", "device": "/dev/comedi0", "subdevice": -1,
//                 "block_samples": 1000, "channels": [DaqChannelScaling x3] (fx, fy, fz) },
//     "lcm": { "url": "udpm://239.255.76.67:7667?ttl=0",
//              "output_url": "udpm://239.255.76.67:7668?ttl=0", "channels": { ChannelNames } },
//     "status_period_s": 1.0,
//     "log_level": "info" }

#include <array>
#include <nlohmann/json.hpp>
#include <string>

#include "core/monitor/monitor_config.hpp"
#include "core/signal/daq_scaling.hpp"
#include "msgs/lcm_output.hpp"

namespace millwatch::daemon {

struct SourceConfig {
  enum class Kind { kLcm, kComedi } kind = Kind::kLcm;
  std::string channel = "MILLWATCH_FORCE_RAW";
  std::string device = "/dev/comedi0";
  int subdevice = -1;        ///< -1: the first analogue input subdevice
  int block_samples = 1000;  ///< Comedi: samples per block, [16, BlockSlot::kMaxSamples]
  /// LCM: a raw block of more samples is dropped (and counted) before it is decoded;
  /// [1, BlockSlot::kMaxSamples].
  int max_block_samples = 4096;
  /// LCM source: the sample thread takes the blocks in rounds about this far apart instead of
  /// waking for each one (a thousand a second at 333.3 kHz cost ~2 % of a core in wake-ups
  /// alone); a block waits about this long (plus the timer's slack) for its round. 0: woken for
  /// every block. [0, 0.1] s. (A Comedi source's reader wakes the sample thread per block.)
  double wake_period_s = 0.005;
  /// LCM source on a udpm:// URL: kBatched reads the group in the sample thread, a round's
  /// datagrams in one system call (daemon/udpm_receiver.hpp); kLcm takes them from LCM's receive
  /// thread, woken for each (and reassembling messages sent in fragments, which kBatched drops
  /// and counts). Other URLs, or a channel that is a regular expression, always use LCM's.
  enum class Receive { kBatched, kLcm } receive = Receive::kBatched;
  std::array<signal::DaqChannelScaling, 3> channels{};  ///< fx, fy, fz
};

struct DaemonConfig {
  monitor::MonitorConfig monitor;
  SourceConfig source;
  /// Where the raw blocks come in (an LCM source).
  std::string lcm_url = "udpm://239.255.76.67:7667?ttl=0";
  /// Where the results go. Its own port by default: every socket on a udpm group and port
  /// receives every datagram sent there, so with one URL the daemon's LCM receive thread would
  /// also read back its own ~1,300 output messages a second (and a subscriber to the results,
  /// the raw stream's 8 MB/s).
  std::string lcm_output_url = "udpm://239.255.76.67:7668?ttl=0";
  messaging::ChannelNames channels;
  double status_period_s = 1.0;
  std::string log_level = "info";
};

/// Whether `url` names an LCM provider this LCM has (udpm, tcpq, file, memq).
/// @throws config::ConfigError(where, ...) if not
void check_lcm_url(const std::string& url, const std::string& where);

/// @throws config::ConfigError naming the field, its value and the allowed range.
DaemonConfig daemon_config_from_json(const nlohmann::json& j);

/// What a reload cannot change in a running daemon — the source, the LCM set-up, and with a
/// Comedi source the sample rate its board scans at (an LCM source's blocks carry their rate):
/// the fields of `next` that differ from `running`, for a warning (empty: none).
[[nodiscard]] std::string fields_needing_restart(const DaemonConfig& running,
                                                 const DaemonConfig& next);
/// What a reload applies: `next` with those fields at their running values.
[[nodiscard]] DaemonConfig as_reload_of(const DaemonConfig& running, DaemonConfig next);

}  // namespace millwatch::daemon
