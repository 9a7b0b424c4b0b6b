// millwatchd's batched udpm receive (daemon/udpm_receiver.hpp, LcmSource on a udpm:// URL): the
// datagrams LCM's own publish sends — the independent sender here — are read in rounds by the
// caller's thread: every block in order and to the bit, a burst larger than one read, other
// channels passed over (one whose name begins with the source's, one's fragments), garbage
// counted, a block LCM had to fragment dropped with its samples counted; the URL's buffer
// applied, and what a full one lost counted by the kernel; a round's wait ends when a block
// comes. The URL is read as LCM reads it.
// The tests that send run alone in a private network namespace (unshare -n; skipped, saying
// why, where that is not permitted), so that no packet leaves the machine.

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "daemon/lcm_source.hpp"
#include "daemon/udpm_receiver.hpp"
#include "msgs/lcm_convert.hpp"
#include "tests/support/private_network.hpp"

namespace millwatch::daemon {
namespace {

const std::string kUrl = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";

std::vector<std::uint8_t> encoded(std::int64_t seq, int n) {
  std::vector<double> fx(static_cast<std::size_t>(n)), fy(fx.size()), fz(fx.size());
  for (std::size_t i = 0; i < fx.size(); ++i) {
    fx[i] = static_cast<double>(seq) + 1e-3 * static_cast<double>(i);
    fy[i] = -fx[i];
    fz[i] = 0.5 * fx[i];
  }
  const force_block_t m = messaging::to_message({seq * 1000, seq, 333300.0, fx, fy, fz});
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

void publish(lcm::LCM& lcm, const std::string& channel, const std::vector<std::uint8_t>& bytes) {
  ASSERT_EQ(lcm.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size())), 0);
}

TEST(UdpmUrl, ReadsGroupPortAndBufferAsLcmDoes) {
  const auto full = parse_udpm_url("udpm://239.255.76.68:7700?ttl=1&recv_buf_size=2097152");
  ASSERT_TRUE(full.has_value());
  EXPECT_EQ(ntohl(full->group.s_addr), 0xefff4c44u);  // 239.255.76.68
  EXPECT_EQ(full->port, 7700);
  EXPECT_EQ(full->recv_buf_size_bytes, 2097152);
  // LCM's defaults where the URL leaves them out.
  for (const char* url : {"udpm://", "udpm://?ttl=0", "udpm://239.255.76.67"}) {
    const auto e = parse_udpm_url(url);
    ASSERT_TRUE(e.has_value()) << url;
    EXPECT_EQ(ntohl(e->group.s_addr), 0xefff4c43u) << url;
    EXPECT_EQ(e->port, 7667) << url;
    EXPECT_EQ(e->recv_buf_size_bytes, 0) << url;
  }
  for (const char* other : {"memq://", "file:///tmp/a.lcmlog", "tcpq://127.0.0.1:7700"}) {
    EXPECT_FALSE(parse_udpm_url(other).has_value()) << other;
  }
  // Numbers as LCM's strtol reads them, the group as its inet_aton does.
  EXPECT_EQ(parse_udpm_url("udpm://239.255.76.67:0x1df3")->port, 7667);
  EXPECT_EQ(parse_udpm_url("udpm://239.255.76.67:7667?recv_buf_size=0x400000")->recv_buf_size_bytes,
            4194304);
  EXPECT_EQ(ntohl(parse_udpm_url("udpm://239.255.76:7667")->group.s_addr), 0xefff004cu);
  // A recv_buf_size LCM cannot read it leaves out (and warns of); a group or port it refuses.
  EXPECT_EQ(parse_udpm_url("udpm://239.255.76.67:7667?recv_buf_size=a")->recv_buf_size_bytes, 0);
  for (const char* bad : {"udpm://239.255.76.300:7667", "udpm://cell-3:7667",
                          "udpm://239.255.76.67:70000", "udpm://239.255.76.67:x"}) {
    EXPECT_FALSE(parse_udpm_url(bad).has_value()) << bad;
  }
}

TEST(UdpmUrl, OnlyAChannelNamedPlainlyIsTakenByName) {
  EXPECT_TRUE(LcmSource::is_plain_channel("MILLWATCH_FORCE_RAW"));
  EXPECT_TRUE(LcmSource::is_plain_channel("cell-3/DYNO:raw"));
  EXPECT_FALSE(LcmSource::is_plain_channel(""));
  EXPECT_FALSE(LcmSource::is_plain_channel("MILLWATCH_.*"));
  EXPECT_FALSE(LcmSource::is_plain_channel("RAW|RAW2"));
  EXPECT_FALSE(LcmSource::is_plain_channel("FORCE.RAW"));
}

TEST(UdpmSource, TakesLcmsDatagramsInRoundsAndCountsWhatIsNoBlock) {
  if (!test::in_private_network()) {
    test::run_alone_in_private_network("UdpmSource.TakesLcms*");
    return;
  }
  lcm::LCM sender(kUrl);
  ASSERT_TRUE(sender.good());
  const auto endpoint = parse_udpm_url(kUrl);
  ASSERT_TRUE(endpoint.has_value());
  auto queue = std::make_unique<BlockQueue>(LcmSource::kQueueCapacity);
  SourceCounters counters;
  LcmSource source(*endpoint, "RAW", 4096, *queue, counters);
  ASSERT_TRUE(source.batched());
  EXPECT_FALSE(source.take_waiting());  // nothing sent yet
  // The URL's buffer (the kernel doubles it, within net.core.rmem_max).
  long rmem_max = 0;
  std::ifstream("/proc/sys/net/core/rmem_max") >> rmem_max;
  EXPECT_GE(source.receive_buffer_bytes(), std::min<long>(4194304, rmem_max));

  // 20 blocks (more than one read's 16), the last of force_block_t's most samples, with an
  // other channel's, garbage and a block LCM must fragment among them.
  constexpr int kBlocks = 20;
  for (int seq = 1; seq <= kBlocks; ++seq) {
    publish(sender, "RAW", encoded(seq, seq == kBlocks ? 2000 : 333));
    if (seq == 5) {
      publish(sender, "OTHER", encoded(500, 333));
      publish(sender, "RAW2", encoded(501, 333));    // a name it begins
      publish(sender, "OTHER", encoded(502, 3000));  // fragments of another channel
    } else if (seq == 10) {
      publish(sender, "RAW", {1, 2, 3});
    } else if (seq == 15) {
      publish(sender, "RAW", encoded(100, 3000));  // 72,036 bytes: two fragments
    }
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // all in the socket's buffer

  std::vector<std::int64_t> seqs;
  auto slot = std::make_unique<BlockSlot>();
  while (source.take_waiting()) {
    while (queue->try_pop(*slot)) {
      seqs.push_back(slot->seq);
      const auto expected = encoded(slot->seq, static_cast<int>(slot->count));
      force_block_t m;
      ASSERT_EQ(m.decode(expected.data(), 0, static_cast<int>(expected.size())),
                static_cast<int>(expected.size()));
      EXPECT_EQ(slot->utime_us, m.utime);
      EXPECT_EQ(slot->sample_rate_hz, m.sample_rate_hz);
      for (std::size_t i = 0; i < slot->count; ++i) {
        ASSERT_EQ(slot->fx[i], m.fx_N[i]);
        ASSERT_EQ(slot->fy[i], m.fy_N[i]);
        ASSERT_EQ(slot->fz[i], m.fz_N[i]);
      }
    }
  }
  std::vector<std::int64_t> in_order(kBlocks);
  for (int i = 0; i < kBlocks; ++i) {
    in_order[static_cast<std::size_t>(i)] = i + 1;
  }
  EXPECT_EQ(seqs, in_order);
  EXPECT_EQ(counters.messages.load(), kBlocks + 2);  // the garbage and the fragmented block
  EXPECT_EQ(counters.undecodable.load(), 1);
  EXPECT_EQ(counters.oversized.load(), 1);  // its 3,000 samples lost, as a block too long
  EXPECT_EQ(counters.samples_dropped.load(), 3000);
  EXPECT_EQ(counters.queue_full.load(), 0);
}

TEST(UdpmSource, AFullBufferSaysHowManyDatagramsTheKernelDropped) {
  if (!test::in_private_network()) {
    test::run_alone_in_private_network("UdpmSource.AFullBuffer*");
    return;
  }
  lcm::LCM sender(kUrl);
  ASSERT_TRUE(sender.good());
  // The kernel's smallest buffer (a few kB): one 8 kB block fills it.
  UdpmReceiver receiver(*parse_udpm_url("udpm://239.255.76.67:7667?ttl=0&recv_buf_size=1"));
  if (!receiver.counts_drops()) {
    GTEST_SKIP() << "this kernel does not count a socket's drops (SO_RXQ_OVFL)";
  }
  const auto drain = [&receiver] {
    std::size_t read = 0;
    while (const std::size_t n = receiver.read_waiting()) {
      read += n;
    }
    return read;
  };
  constexpr int kBlocks = 30;
  for (int seq = 1; seq <= kBlocks; ++seq) {
    publish(sender, "RAW", encoded(seq, 333));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  std::size_t read = drain();
  // The count comes with the next datagram queued after the drops.
  publish(sender, "RAW", encoded(kBlocks + 1, 333));
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  read += drain();
  EXPECT_GE(receiver.dropped_datagrams(), 20u) << read << " read";
  EXPECT_EQ(read + receiver.dropped_datagrams(), static_cast<std::size_t>(kBlocks + 1));
}

TEST(UdpmSource, AWaitEndsWhenABlockComes) {
  if (!test::in_private_network()) {
    test::run_alone_in_private_network("UdpmSource.AWait*");
    return;
  }
  lcm::LCM sender(kUrl);
  ASSERT_TRUE(sender.good());
  auto queue = std::make_unique<BlockQueue>(LcmSource::kQueueCapacity);
  SourceCounters counters;
  LcmSource source(*parse_udpm_url(kUrl), "RAW", 4096, *queue, counters);
  const auto t0 = std::chrono::steady_clock::now();
  source.wait(std::chrono::milliseconds(50));  // none comes: back after its timeout
  EXPECT_GE(std::chrono::steady_clock::now() - t0, std::chrono::milliseconds(45));
  EXPECT_EQ(queue->front(), nullptr);

  std::thread late([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    publish(sender, "RAW", encoded(1, 333));
  });
  const auto t1 = std::chrono::steady_clock::now();
  source.wait(std::chrono::seconds(20));
  const auto waited = std::chrono::steady_clock::now() - t1;
  late.join();
  ASSERT_NE(queue->front(), nullptr);
  EXPECT_EQ(queue->front()->seq, 1);
  EXPECT_LT(waited, std::chrono::seconds(10));  // woken by the block, not the timeout
}

}  // namespace
}  // namespace millwatch::daemon
