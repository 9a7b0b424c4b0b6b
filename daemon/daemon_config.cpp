#include "daemon/daemon_config.hpp"

#include "core/config/json_reader.hpp"
#include "daemon/block_queue.hpp"

namespace millwatch::daemon {
namespace {

using config::ObjectReader;

SourceConfig read_source(ObjectReader r, std::array<double, 3>& saturation_N) {
  SourceConfig s;
  s.kind = r.choice("kind", "lcm", {"lcm", "comedi"}) == "comedi" ? SourceConfig::Kind::kComedi
                                                                  : SourceConfig::Kind::kLcm;
  s.channel = r.string("channel", s.channel);
  s.device = r.string("device", s.device);
  s.subdevice = r.integer("subdevice", s.subdevice, -1, 64);
  constexpr int kSlot = static_cast<int>(BlockSlot::kMaxSamples);
  s.block_samples = r.integer("block_samples", s.block_samples, 16, kSlot);
  s.max_block_samples = r.integer("max_block_samples", s.max_block_samples, 1, kSlot);
  s.wake_period_s = r.number("wake_period_s", s.wake_period_s, config::closed(0.0, 0.1, "s"));
  s.receive = r.choice("receive", "batched", {"batched", "lcm"}) == "lcm"
                  ? SourceConfig::Receive::kLcm
                  : SourceConfig::Receive::kBatched;
  const nlohmann::json& channels = r.raw("channels");
  if (s.kind == SourceConfig::Kind::kComedi) {
    if (!channels.is_array() || channels.size() != 3) {
      config::fail(r.path_of("channels"),
                   "a Comedi source needs three channels (fx, fy, fz), got " +
                       config::describe_json(channels));
    }
    for (std::size_t a = 0; a < 3; ++a) {
      s.channels[a] = signal::daq_channel_from_json(
          channels[a], r.path_of("channels") + "[" + std::to_string(a) + "]");
      saturation_N[a] = s.channels[a].range_N;  // saturated samples come out at ±range
    }
  } else if (!channels.is_null()) {
    config::fail(r.path_of("channels"), "only a Comedi source has channels");
  }
  r.finish();
  return s;
}

messaging::ChannelNames read_channels(ObjectReader r) {
  messaging::ChannelNames c;
  c.raw = r.string("raw", c.raw);
  c.spindle = r.string("spindle", c.spindle);
  c.tooth_periods = r.string("tooth_periods", c.tooth_periods);
  c.flute_peaks = r.string("flute_peaks", c.flute_peaks);
  c.residual = r.string("residual", c.residual);
  c.sync_average = r.string("sync_average", c.sync_average);
  c.runout = r.string("runout", c.runout);
  c.coefficients = r.string("coefficients", c.coefficients);
  c.alert = r.string("alert", c.alert);
  c.status = r.string("status", c.status);
  r.finish();
  return c;
}

/// An LCM URL: "provider://..." (udpm://, memq://, file://, tcpq://); LCM itself only says
/// "cannot open" at start.
std::string read_url(ObjectReader& r, std::string_view key, const std::string& fallback) {
  std::string url = r.string(key, fallback);
  check_lcm_url(url, r.path_of(key));
  return url;
}

}  // namespace

void check_lcm_url(const std::string& url, const std::string& where) {
  const auto scheme = url.find("://");
  if (scheme == std::string::npos || scheme == 0) {
    config::fail(where, "\"" + url +
                            "\" is not an LCM URL (provider://..., e.g. "
                            "udpm://239.255.76.67:7667?ttl=0)");
  }
  // LCM 1.3.1's providers: another name fails only when the daemon starts, with a hint about
  // multicast routes that does not apply.
  const std::string provider = url.substr(0, scheme);
  if (provider != "udpm" && provider != "tcpq" && provider != "file" && provider != "memq") {
    config::fail(where, "\"" + url + "\": no LCM provider \"" + provider +
                            "\" (LCM 1.3.1 has udpm, tcpq, file and memq)");
  }
}

DaemonConfig daemon_config_from_json(const nlohmann::json& j) {
  ObjectReader r(j, "");
  DaemonConfig c;
  c.monitor = monitor::monitor_config_from_json(r.raw("monitor"), "monitor");
  c.source = read_source(r.object("source"), c.monitor.saturation_N);
  {
    auto l = r.object("lcm");
    c.lcm_url = read_url(l, "url", c.lcm_url);
    c.lcm_output_url = read_url(l, "output_url", c.lcm_output_url);
    c.channels = read_channels(l.object("channels"));
    l.finish();
  }
  c.status_period_s =
      r.number("status_period_s", c.status_period_s, config::closed(0.01, 3600.0, "s"));
  c.log_level = r.choice("log_level", c.log_level, {"trace", "debug", "info", "warn", "error"});
  r.finish();
  if (c.source.kind == SourceConfig::Kind::kLcm && c.source.channel != c.channels.raw) {
    c.channels.raw = c.source.channel;
  }
  return c;
}

std::string fields_needing_restart(const DaemonConfig& running, const DaemonConfig& next) {
  std::string out;
  auto note = [&out](bool differs, const char* field) {
    if (differs) {
      out += (out.empty() ? "" : ", ") + std::string(field);
    }
  };
  const auto& a = running.source;
  const auto& b = next.source;
  note(a.kind != b.kind, "source.kind");
  note(a.channel != b.channel, "source.channel");
  note(a.device != b.device, "source.device");
  note(a.subdevice != b.subdevice, "source.subdevice");
  note(a.block_samples != b.block_samples, "source.block_samples");
  note(a.max_block_samples != b.max_block_samples, "source.max_block_samples");
  note(a.wake_period_s != b.wake_period_s, "source.wake_period_s");
  note(a.receive != b.receive && b.kind == SourceConfig::Kind::kLcm, "source.receive");
  // A Comedi board scans at the rate it was started with; an LCM source's blocks carry theirs.
  note(a.kind == SourceConfig::Kind::kComedi &&
           running.monitor.sample_rate_hz != next.monitor.sample_rate_hz,
       "monitor.sample_rate_hz (the Comedi board's scan rate)");
  bool channels_differ = false;
  for (std::size_t i = 0; i < a.channels.size(); ++i) {
    const auto& x = a.channels[i];
    const auto& y = b.channels[i];
    channels_differ = channels_differ || x.daq_channel != y.daq_channel ||
                      x.volts_min != y.volts_min || x.volts_max != y.volts_max ||
                      x.maxdata != y.maxdata || x.range_N != y.range_N ||
                      x.full_scale_V != y.full_scale_V;
  }
  note(channels_differ, "source.channels");
  note(running.lcm_url != next.lcm_url, "lcm.url");
  note(running.lcm_output_url != next.lcm_output_url, "lcm.output_url");
  const auto& c = running.channels;
  const auto& d = next.channels;
  // For an LCM source, lcm.channels.raw follows source.channel (noted above).
  note((c.raw != d.raw && a.channel == b.channel) || c.spindle != d.spindle ||
           c.tooth_periods != d.tooth_periods || c.flute_peaks != d.flute_peaks ||
           c.residual != d.residual || c.sync_average != d.sync_average || c.runout != d.runout ||
           c.coefficients != d.coefficients || c.alert != d.alert || c.status != d.status,
       "lcm.channels");
  return out;
}

DaemonConfig as_reload_of(const DaemonConfig& running, DaemonConfig next) {
  const bool comedi = running.source.kind == SourceConfig::Kind::kComedi;
  if (comedi || next.source.kind != running.source.kind) {
    // A Comedi channel saturates at its amplifier's range (read_source): the running channels'
    // (an LCM source's: the running monitor section's, not a Comedi file's channels').
    next.monitor.saturation_N = running.monitor.saturation_N;
  }
  if (comedi) {
    next.monitor.sample_rate_hz = running.monitor.sample_rate_hz;  // the board's scan rate
    monitor::choose_cutoff_for_cut(next.monitor);                  // one not given suits that rate
  }
  next.source = running.source;
  next.lcm_url = running.lcm_url;
  next.lcm_output_url = running.lcm_output_url;
  next.channels = running.channels;
  return next;
}

}  // namespace millwatch::daemon
