#include "replay/stop_signal.hpp"

#include <csignal>

namespace millwatch::shell {
namespace {

volatile std::sig_atomic_t g_stop = 0;

extern "C" void on_stop_signal(int signal) {
  g_stop = signal;
}

}  // namespace

void install_stop_signals(InterruptedCalls calls) {
  g_stop = 0;
  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = calls == InterruptedCalls::restart ? SA_RESTART : 0;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

bool stop_requested() {
  return g_stop != 0;
}

int stop_signal() {
  return g_stop;
}

int interrupted_exit_status() {
  return 128 + (g_stop != 0 ? static_cast<int>(g_stop) : SIGINT);
}

bool is_interrupted_exit_status(int status) {
  return status == 128 + SIGINT || status == 128 + SIGTERM;
}

}  // namespace millwatch::shell
