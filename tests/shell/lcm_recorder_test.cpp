// The LCM log recorder: on memq://, every message of the matched channels in order, read back by
// the replay's LCM log reader to the same samples; the inverted match; a bad expression, an
// unwritable file and a full disk are errors naming them. Over udpm:// in a private network
// namespace (memq does not queue), 400 messages waiting before it runs, where a subscription with
// LCM's default queue (lcm-logger's) keeps 30.

#include "shell/lcm_recorder.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <lcm/lcm-cpp.hpp>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "msgs/lcm_convert.hpp"
#include "shell/lcm_log_reader.hpp"
#include "tests/support/private_network.hpp"
#include "tests/support/test_paths.hpp"

namespace millwatch::shell {
namespace {

namespace fs = std::filesystem;

constexpr const char* kRaw = "MILLWATCH_FORCE_RAW";

/// A block of `n` samples whose values tell its sequence number and each sample apart.
force_block_t block(std::int64_t seq, int n) {
  std::vector<double> fx, fy, fz;
  for (int i = 0; i < n; ++i) {
    fx.push_back(static_cast<double>(seq) + 0.001 * i);
    fy.push_back(-static_cast<double>(seq) - 0.001 * i);
    fz.push_back(0.5 * static_cast<double>(i));
  }
  return messaging::to_message({seq * 1000, seq, 50000.0, fx, fy, fz});
}

/// Publishes `blocks` raw blocks of 250 samples, each followed by a message on STATUS, all
/// before the recorder handles any.
void publish(lcm::LCM& lcm, int blocks) {
  for (int s = 0; s < blocks; ++s) {
    const force_block_t b = block(s, 250);
    lcm.publish(kRaw, &b);
    const std::vector<std::uint8_t> status = {1, 2, static_cast<std::uint8_t>(s)};
    lcm.publish("STATUS", status.data(), static_cast<unsigned>(status.size()));
  }
}

void drain(LcmRecorder& recorder) {
  while (recorder.handle(0)) {
  }
  recorder.finish();
}

TEST(LcmRecorder, KeepsEveryMessageOfTheMatchedChannelsHoweverManyWait) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  const fs::path path = test::fresh_temp_dir() / "raw.lcmlog";
  LcmRecorder recorder(lcm.getUnderlyingLCM(), path, kRaw);
  constexpr int kBlocks = 400;  // lcm-logger 1.3.1 keeps 30 waiting
  publish(lcm, kBlocks);
  drain(recorder);
  EXPECT_EQ(recorder.events(), kBlocks);
  ASSERT_EQ(recorder.per_channel().size(), 1u);
  EXPECT_EQ(recorder.per_channel().at(kRaw), kBlocks);

  std::vector<std::string> problems;
  LcmLogReader reader(path, kRaw,
                      [&](std::int64_t, const std::string& p) { problems.push_back(p); });
  std::int64_t seq = 0;
  while (const auto b = reader.next()) {
    ASSERT_EQ(b->seq, seq);
    ASSERT_EQ(b->fx_N.size(), 250u);
    EXPECT_EQ(b->sample_rate_hz, 50000.0);
    EXPECT_EQ(b->fx_N[249], static_cast<double>(seq) + 0.001 * 249);
    EXPECT_EQ(b->fy_N[7], -static_cast<double>(seq) - 0.001 * 7);
    EXPECT_EQ(b->fz_N[100], 50.0);
    ++seq;
  }
  EXPECT_EQ(seq, kBlocks);
  EXPECT_TRUE(problems.empty());
  EXPECT_EQ(reader.events(), kBlocks);
}

TEST(LcmRecorder, InvertedItKeepsEveryOtherChannel) {
  lcm::LCM lcm("memq://");
  const fs::path path = test::fresh_temp_dir() / "others.lcmlog";
  LcmRecorder recorder(lcm.getUnderlyingLCM(), path, "MILLWATCH_FORCE_.*", true);
  publish(lcm, 50);
  drain(recorder);
  EXPECT_EQ(recorder.events(), 50);
  EXPECT_EQ(recorder.bytes(), 150);
  ASSERT_EQ(recorder.per_channel().size(), 1u);
  EXPECT_EQ(recorder.per_channel().at("STATUS"), 50);
  lcm::LogFile log(path.string(), "r");
  int events = 0;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    ASSERT_EQ(e->channel, "STATUS");
    ASSERT_EQ(e->datalen, 3);
    EXPECT_EQ(static_cast<const std::uint8_t*>(e->data)[2], events);
    EXPECT_EQ(e->eventnum, events);
    ++events;
  }
  EXPECT_EQ(events, 50);
}

TEST(LcmRecorder, TheExpressionMatchesTheWholeName) {
  lcm::LCM lcm("memq://");
  const fs::path path = test::fresh_temp_dir() / "whole.lcmlog";
  LcmRecorder recorder(lcm.getUnderlyingLCM(), path, "STAT");  // not STATUS
  publish(lcm, 5);
  drain(recorder);
  EXPECT_EQ(recorder.events(), 0);
}

/// The message of what `f` throws (empty if nothing).
template <class F>
std::string thrown(F&& f) {
  try {
    f();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return {};
}

TEST(LcmRecorder, ABadExpressionOrFileIsAnErrorNamingIt) {
  lcm::LCM lcm("memq://");
  const fs::path dir = test::fresh_temp_dir();
  const std::string bad_regex =
      thrown([&] { LcmRecorder r(lcm.getUnderlyingLCM(), dir / "a.lcmlog", "MILL(WATCH"); });
  EXPECT_NE(bad_regex.find("bad channel regular expression 'MILL(WATCH'"), std::string::npos)
      << bad_regex;
  const fs::path nowhere = dir / "no" / "such" / "folder" / "a.lcmlog";
  const std::string no_file = thrown([&] { LcmRecorder r(lcm.getUnderlyingLCM(), nowhere, ".*"); });
  EXPECT_NE(no_file.find(nowhere.string() + ": cannot write"), std::string::npos) << no_file;
}

TEST(LcmRecorder, AFullDiskStopsItWithAnErrorNamingTheFileAndTheEvent) {
  if (!fs::exists("/dev/full")) {
    GTEST_SKIP() << "no /dev/full";
  }
  lcm::LCM lcm("memq://");
  LcmRecorder recorder(lcm.getUnderlyingLCM(), "/dev/full", kRaw);
  publish(lcm, 3);  // 6 KB each: more than stdio's buffer, so the first write reaches the file
  const std::string error = thrown([&] { drain(recorder); });
  EXPECT_NE(error.find("/dev/full: cannot write event 1 (MILLWATCH_FORCE_RAW"), std::string::npos)
      << error;
  EXPECT_NE(error.find("No space left on device"), std::string::npos) << error;
}

TEST(LcmRecorder, OverUdpmItKeepsMoreThanLcmLoggersThirtyWaiting) {
  if (!test::in_private_network()) {  // this test again, alone, in a private namespace
    test::run_alone_in_private_network("LcmRecorder.OverUdpm*");
    return;
  }
  const std::string url = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";
  lcm::LCM recording(url), plain(url), publisher(url);
  ASSERT_TRUE(recording.good() && plain.good() && publisher.good());
  const fs::path path = test::fresh_temp_dir() / "udpm.lcmlog";
  LcmRecorder recorder(recording.getUnderlyingLCM(), path, "STATUS");
  int plain_received = 0;  // a subscription as lcm-logger makes it
  plain.subscribeFunction(
      "STATUS", +[](const lcm::ReceiveBuffer*, const std::string&, int* n) { ++*n; },
      &plain_received);
  constexpr int kMessages = 400;
  for (int s = 0; s < kMessages; ++s) {
    const std::vector<std::uint8_t> status = {1, 2, static_cast<std::uint8_t>(s % 200)};
    publisher.publish("STATUS", status.data(), static_cast<unsigned>(status.size()));
  }
  // Nobody handles a message until every one is in LCM's receive threads' queues.
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  drain(recorder);
  while (plain.handleTimeout(0) > 0) {
  }
  EXPECT_EQ(recorder.events(), kMessages);
  // What the recorder would have kept with LCM's default queue.
  EXPECT_LE(plain_received, 31) << plain_received;
  lcm::LogFile log(path.string(), "r");
  int events = 0;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    ASSERT_EQ(e->datalen, 3);
    EXPECT_EQ(static_cast<const std::uint8_t*>(e->data)[2], events % 200);
    ++events;
  }
  EXPECT_EQ(events, kMessages);
}

}  // namespace
}  // namespace millwatch::shell
