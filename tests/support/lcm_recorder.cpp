// The recorder of the tests' multi-process LCM sessions (tests/daemon/lcm_session.sh): what
// lcm-logger does, an LCM event log of the channels a regular expression matches, but with no
// limit on the messages its subscription queues. lcm-logger 1.3.1 queues 30 and drops the rest
// when its thread is slow to run: on a busy 2-core VM, at real-time priority, it lost runs of 6
// to 25 revolutions' results of millwatchd (and once a raw block) while the kernel dropped
// nothing (Udp RcvbufErrors 0) and the daemon had published every message. A test of the daemon
// must not fail for its recorder's queue.
//
//   lcm_recorder URL REGEX FILE [--invert]
//
// REGEX, a POSIX extended regular expression, must match a channel's whole name (--invert: every
// channel it does not match). Runs until SIGINT or SIGTERM, then closes the log and exits 0.
// POSIX <regex.h> rather than std::regex: GCC 12's <regex> warns (maybe-uninitialized, a false
// positive inside std::function) in the -O1 sanitizer build, whose warnings are errors.

#include <lcm/eventlog.h>
#include <lcm/lcm.h>
#include <regex.h>

#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>

namespace {

volatile std::sig_atomic_t g_stop = 0;

void on_signal(int) {
  g_stop = 1;
}

struct Recorder {
  lcm_eventlog_t* log = nullptr;
  regex_t channels{};
  bool invert = false;
  std::int64_t events = 0;
};

void on_message(const lcm_recv_buf_t* rbuf, const char* channel, void* user) {
  auto& r = *static_cast<Recorder*>(user);
  if ((regexec(&r.channels, channel, 0, nullptr, 0) == 0) == r.invert) {
    return;
  }
  lcm_eventlog_event_t e{};
  e.eventnum = r.events++;
  e.timestamp = rbuf->recv_utime;
  e.channellen = static_cast<std::int32_t>(std::strlen(channel));
  e.datalen = static_cast<std::int32_t>(rbuf->data_size);
  e.channel = const_cast<char*>(channel);  // NOLINT: the C API's event is not const
  e.data = rbuf->data;
  if (lcm_eventlog_write_event(r.log, &e) != 0) {
    std::fprintf(stderr, "lcm_recorder: could not write event %lld\n",
                 static_cast<long long>(e.eventnum));
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4 || argc > 5 || (argc == 5 && std::string(argv[4]) != "--invert")) {
    std::fprintf(stderr, "usage: lcm_recorder URL REGEX FILE [--invert]\n");
    return 2;
  }
  struct sigaction sa {};
  sa.sa_handler = on_signal;  // no SA_RESTART: the wait below returns at once
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  Recorder r;
  const std::string whole = "^(" + std::string(argv[2]) + ")$";
  if (const int err = regcomp(&r.channels, whole.c_str(), REG_EXTENDED | REG_NOSUB); err != 0) {
    char what[256];
    regerror(err, &r.channels, what, sizeof what);
    std::fprintf(stderr, "lcm_recorder: bad regular expression '%s': %s\n", argv[2], what);
    return 2;
  }
  r.invert = argc == 5;
  lcm_t* lcm = lcm_create(argv[1]);
  if (lcm == nullptr) {
    std::fprintf(stderr, "lcm_recorder: cannot open LCM on %s\n", argv[1]);
    regfree(&r.channels);
    return 1;
  }
  r.log = lcm_eventlog_create(argv[3], "w");
  if (r.log == nullptr) {
    std::fprintf(stderr, "lcm_recorder: cannot write %s\n", argv[3]);
    lcm_destroy(lcm);
    regfree(&r.channels);
    return 1;
  }
  lcm_subscription_t* sub = lcm_subscribe(lcm, ".*", on_message, &r);
  lcm_subscription_set_queue_capacity(sub, 0);  // no limit
  while (g_stop == 0) {
    lcm_handle_timeout(lcm, 100);
  }
  // What arrived before the signal and is still queued.
  while (lcm_handle_timeout(lcm, 0) > 0) {
  }
  lcm_unsubscribe(lcm, sub);
  lcm_eventlog_destroy(r.log);
  lcm_destroy(lcm);
  regfree(&r.channels);
  std::fprintf(stderr, "lcm_recorder: %lld events in %s\n", static_cast<long long>(r.events),
               argv[3]);
  return 0;
}
