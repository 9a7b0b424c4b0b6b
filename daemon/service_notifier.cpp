#include "daemon/service_notifier.hpp"

#include <systemd/sd-daemon.h>

#include <cstdlib>

namespace millwatch::daemon {

ServiceNotifier::ServiceNotifier() {
  const char* socket = std::getenv("NOTIFY_SOCKET");
  enabled_ = socket != nullptr && socket[0] != '\0';
  std::uint64_t usec = 0;
  if (enabled_ && sd_watchdog_enabled(0, &usec) > 0 && usec > 0) {
    interval_ = std::chrono::microseconds(usec);
  }
  next_ping_ = std::chrono::steady_clock::now();
}

void ServiceNotifier::send(const char* text) {
  if (enabled_) {
    sd_notify(0, text);
  }
}

void ServiceNotifier::ready(const std::string& status) {
  send(("READY=1\nSTATUS=" + status).c_str());
}

void ServiceNotifier::reloading() {
  send("RELOADING=1\nSTATUS=reloading the configuration");
}

void ServiceNotifier::stopping() {
  send("STOPPING=1\nSTATUS=stopping: draining the queue");
}

void ServiceNotifier::status(const std::string& status) {
  send(("STATUS=" + status).c_str());
}

void ServiceNotifier::watchdog() {
  if (interval_.count() == 0) {
    return;
  }
  const auto now = std::chrono::steady_clock::now();
  if (now < next_ping_) {
    return;
  }
  next_ping_ = now + interval_ / 2;
  sd_notify(0, "WATCHDOG=1");
  pings_.fetch_add(1);
}

}  // namespace millwatch::daemon
