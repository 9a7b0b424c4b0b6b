// millwatchd under a service manager, faked: a NOTIFY_SOCKET of our own receives READY=1 once the
// source is open, WATCHDOG=1 at half WATCHDOG_USEC from the sample loop — and no more pings once
// the sample thread stalls (--test-stall-sample-thread) —, RELOADING=1/READY=1 around SIGHUP and
// STOPPING=1 on SIGTERM. Also: the unit file passes `systemd-analyze verify`.

#include "daemon/service_notifier.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tests/support/run_command.hpp"
#include "tests/support/test_paths.hpp"

extern char** environ;

namespace millwatch {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

struct Message {
  double t_s;  // since the daemon started
  std::string text;
};

/// A bound AF_UNIX datagram socket, as systemd's notification socket.
class NotifySocket {
 public:
  explicit NotifySocket(const fs::path& path) : path_(path) {
    fs::remove(path);
    fd_ = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_un a{};
    a.sun_family = AF_UNIX;
    const std::string p = path.string();
    if (p.size() >= sizeof a.sun_path) {
      return;  // too long for an AF_UNIX address: not bound
    }
    std::snprintf(a.sun_path, sizeof a.sun_path, "%s", p.c_str());
    bound_ = bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
    timeval tv{0, 20000};
    setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  }
  ~NotifySocket() {
    close(fd_);
    fs::remove(path_);
  }
  [[nodiscard]] bool bound() const { return bound_; }
  /// Messages received until `until`.
  void receive(Clock::time_point start, Clock::time_point until, std::vector<Message>& out) {
    char buffer[4096];
    while (Clock::now() < until) {
      const ssize_t n = recv(fd_, buffer, sizeof buffer, 0);
      if (n > 0) {
        out.push_back({std::chrono::duration<double>(Clock::now() - start).count(),
                       std::string(buffer, static_cast<std::size_t>(n))});
      }
    }
  }

 private:
  fs::path path_;
  int fd_ = -1;
  bool bound_ = false;
};

pid_t start_daemon(const std::vector<std::string>& args, const std::vector<std::string>& env,
                   const fs::path& log) {
  std::vector<char*> argv;
  for (const auto& a : args) {
    argv.push_back(const_cast<char*>(a.c_str()));
  }
  argv.push_back(nullptr);
  std::vector<std::string> env_text;
  for (char** e = environ; *e != nullptr; ++e) {
    const std::string v = *e;
    if (v.rfind("NOTIFY_SOCKET=", 0) != 0 && v.rfind("WATCHDOG_", 0) != 0) {
      env_text.push_back(v);
    }
  }
  env_text.insert(env_text.end(), env.begin(), env.end());
  std::vector<char*> envp;
  for (auto& e : env_text) {
    envp.push_back(e.data());
  }
  envp.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 2, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, args[0].c_str(), &actions, nullptr, argv.data(), envp.data());
  posix_spawn_file_actions_destroy(&actions);
  EXPECT_EQ(rc, 0);
  return pid;
}

int wait_exit(pid_t pid) {
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::vector<double> pings(const std::vector<Message>& m) {
  std::vector<double> t;
  for (const auto& x : m) {
    if (x.text == "WATCHDOG=1") {
      t.push_back(x.t_s);
    }
  }
  return t;
}

/// A socket path short enough for sun_path (108 bytes), unique to this process and test.
fs::path socket_path(const char* name) {
  return fs::temp_directory_path() / ("mw-" + std::to_string(getpid()) + "-" + name + ".sock");
}

std::string config() {
  return (test::source_dir() / "config" / "millwatchd.json").string();
}

TEST(ServiceNotifier, ReadyThenWatchdogPingsThatStopWhenTheSampleThreadStalls) {
  const fs::path dir = test::fresh_temp_dir();
  NotifySocket sock(socket_path("stall"));
  ASSERT_TRUE(sock.bound());
  const auto start = Clock::now();
  const pid_t pid =
      start_daemon({MILLWATCH_DAEMON, "-c", config(), "--lcm-url", "memq://",
                    "--test-stall-sample-thread", "1.5"},
                   {"NOTIFY_SOCKET=" + socket_path("stall").string(), "WATCHDOG_USEC=200000"},
                   dir / "daemon.log");
  std::vector<Message> m;
  sock.receive(start, start + std::chrono::milliseconds(3500), m);
  kill(pid, SIGHUP);
  sock.receive(start, Clock::now() + std::chrono::milliseconds(500), m);
  kill(pid, SIGTERM);
  sock.receive(start, Clock::now() + std::chrono::milliseconds(500), m);
  EXPECT_EQ(wait_exit(pid), 0);
  std::stringstream all;
  for (const auto& x : m) {
    all << x.t_s << " s: " << x.text << "\n";
  }
  ASSERT_FALSE(m.empty()) << "nothing received";
  // READY=1 first, with a status naming the source.
  EXPECT_EQ(m[0].text.rfind("READY=1\nSTATUS=monitoring: source lcm:MILLWATCH_FORCE_RAW", 0), 0u)
      << all.str();
  // Pings every 0.1 s while the sample loop runs (up to 1.5 s) ...
  const std::vector<double> t = pings(m);
  ASSERT_GE(t.size(), 10u) << all.str();
  EXPECT_LT(t.front(), 0.5) << all.str();
  for (std::size_t i = 1; i < t.size(); ++i) {
    EXPECT_LT(t[i] - t[i - 1], 0.25) << "a gap in the pings at " << t[i] << " s\n" << all.str();
  }
  // ... and none once it stalls, although the daemon lives on (it answers SIGHUP).
  EXPECT_GT(t.back(), 1.2) << all.str();
  EXPECT_LT(t.back(), 1.8) << all.str();
  std::vector<std::string> after;
  for (const auto& x : m) {
    if (x.t_s > t.back() && x.text != "WATCHDOG=1") {
      after.push_back(x.text.substr(0, x.text.find('\n')));
    }
  }
  EXPECT_EQ(after, (std::vector<std::string>{"RELOADING=1", "READY=1", "STOPPING=1"})) << all.str();
}

TEST(ServiceNotifier, NoWatchdogAskedNoPingsAndNoSocketNoHarm) {
  const fs::path dir = test::fresh_temp_dir();
  NotifySocket sock(socket_path("plain"));
  ASSERT_TRUE(sock.bound());
  const auto start = Clock::now();
  const pid_t pid =
      start_daemon({MILLWATCH_DAEMON, "-c", config(), "--lcm-url", "memq://"},
                   {"NOTIFY_SOCKET=" + socket_path("plain").string()}, dir / "daemon.log");
  std::vector<Message> m;
  sock.receive(start, start + std::chrono::milliseconds(800), m);
  kill(pid, SIGTERM);
  sock.receive(start, Clock::now() + std::chrono::milliseconds(300), m);
  EXPECT_EQ(wait_exit(pid), 0);
  ASSERT_EQ(m.size(), 2u);
  EXPECT_EQ(m[0].text.rfind("READY=1", 0), 0u);
  EXPECT_EQ(m[1].text.rfind("STOPPING=1", 0), 0u);
  // Not under systemd at all: the notifier does nothing.
  unsetenv("NOTIFY_SOCKET");
  const daemon::ServiceNotifier off;
  EXPECT_FALSE(off.enabled());
  EXPECT_EQ(off.watchdog_interval().count(), 0);
}

// A source that ends (a DAQ whose reads fail) does not leave a live daemon that measures
// nothing: it stops as on SIGTERM — STOPPING=1, the final summary written — and exits 1, which
// the unit's Restart=on-failure answers.
TEST(ServiceNotifier, ASourceThatEndsStopsTheDaemonWithExitStatusOne) {
  const fs::path dir = test::fresh_temp_dir();
  NotifySocket sock(socket_path("ends"));
  ASSERT_TRUE(sock.bound());
  const auto start = Clock::now();
  const pid_t pid =
      start_daemon({MILLWATCH_DAEMON, "-c", config(), "--lcm-url", "memq://", "--summary",
                    (dir / "summary.json").string(), "--test-source-ends-after", "0.5"},
                   {"NOTIFY_SOCKET=" + socket_path("ends").string()}, dir / "daemon.log");
  std::vector<Message> m;
  sock.receive(start, start + std::chrono::milliseconds(2000), m);
  EXPECT_EQ(wait_exit(pid), 1);  // by itself, no signal sent
  const std::string log = test::read_text(dir / "daemon.log");
  EXPECT_NE(log.find("the source has ended: millwatchd stops (exit status 1)"), std::string::npos)
      << log;
  EXPECT_NE(log.find("the source has ended: stopping"), std::string::npos) << log;
  EXPECT_TRUE(fs::exists(dir / "summary.json")) << log;
  ASSERT_EQ(m.size(), 2u) << log;
  EXPECT_EQ(m[0].text.rfind("READY=1", 0), 0u);
  EXPECT_EQ(m[1].text.rfind("STOPPING=1", 0), 0u);
  EXPECT_GT(m[1].t_s, 0.4);
}

TEST(ServiceUnit, PassesSystemdAnalyzeVerify) {
  if (test::run_command("command -v systemd-analyze").exit_code != 0) {
    GTEST_SKIP() << "systemd-analyze is not installed";
  }
  // The unit as `cmake --install` writes it, with the paths of this build's programs.
  const fs::path dir = test::fresh_temp_dir();
  std::ifstream in(test::source_dir() / "packaging" / "millwatchd.service.in");
  std::stringstream s;
  s << in.rdbuf();
  std::string unit = s.str();
  auto replace_all = [&unit](const std::string& from, const std::string& to) {
    for (auto at = unit.find(from); at != std::string::npos; at = unit.find(from, at + to.size())) {
      unit.replace(at, from.size(), to);
    }
  };
  replace_all("@MW_BINDIR@/millwatchd", MILLWATCH_DAEMON);
  replace_all("@MW_SYSCONFDIR@/millwatch/millwatchd.json", config());
  replace_all("@MW_DOCDIR@", (test::source_dir()).string());
  ASSERT_EQ(unit.find('@'), std::string::npos) << unit;
  std::ofstream(dir / "millwatchd.service") << unit;
  const auto r =
      test::run_command("systemd-analyze verify " + (dir / "millwatchd.service").string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output, "") << "systemd-analyze has something to say";
  for (const char* key : {"Type=notify", "WatchdogSec=", "Restart=on-failure", "User=millwatch",
                          "ExecReload=/bin/kill -HUP $MAINPID"}) {
    EXPECT_NE(unit.find(key), std::string::npos) << key;
  }
  // It would notice a mistake: verify is not silent on a broken unit.
  replace_all("Type=notify", "Type=notified");
  std::ofstream(dir / "broken.service") << unit;
  const auto broken =
      test::run_command("systemd-analyze verify " + (dir / "broken.service").string());
  EXPECT_NE(broken.output.find("Failed to parse service type"), std::string::npos) << broken.output;
}

}  // namespace
}  // namespace millwatch
