#pragma once
// millwatchd under systemd (Type=notify, WatchdogSec=): the service manager's notifications
// through libsystemd's sd_notify. READY=1 once the source is open, RELOADING=1 … READY=1 around a
// reload, STOPPING=1 at the end, STATUS= lines for `systemctl status`, and WATCHDOG=1 from the
// sample loop at half the watchdog interval (WATCHDOG_USEC), so that a stalled sample thread
// stops the pings and systemd restarts the daemon. Without NOTIFY_SOCKET (not run by systemd)
// every call does nothing.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <string>

namespace millwatch::daemon {

class ServiceNotifier {
 public:
  /// Reads NOTIFY_SOCKET and the watchdog interval (sd_watchdog_enabled) once.
  ServiceNotifier();

  void ready(const std::string& status);
  void reloading();
  void stopping();
  void status(const std::string& status);
  /// From the sample loop, as often as it likes: pings when half the interval has passed.
  /// Cheap otherwise (a clock read); no allocation.
  void watchdog();

  [[nodiscard]] bool enabled() const { return enabled_; }
  /// The watchdog interval systemd asked for (0: no watchdog).
  [[nodiscard]] std::chrono::microseconds watchdog_interval() const { return interval_; }
  /// WATCHDOG=1 messages sent so far.
  [[nodiscard]] std::int64_t pings() const { return pings_.load(); }

 private:
  void send(const char* text);

  bool enabled_ = false;
  std::chrono::microseconds interval_{0};
  std::chrono::steady_clock::time_point next_ping_{};
  std::atomic<std::int64_t> pings_{0};
};

}  // namespace millwatch::daemon
