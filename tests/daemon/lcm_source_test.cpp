// millwatchd's LCM source in process (memq://): malformed raw messages — a count that wraps
// lcm-gen's size check, a negative count, short and long buffers, garbage, more samples than
// source.max_block_samples — are counted and dropped before decoding; good blocks still arrive.
// In steady state a block costs the source no heap allocation on its way into the queue.

#include "daemon/lcm_source.hpp"

#include <gtest/gtest.h>

#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <set>
#include <vector>

#include "msgs/lcm_convert.hpp"
#include "tests/support/allocation_counter.hpp"

namespace millwatch::daemon {
namespace {

std::vector<std::uint8_t> encoded(std::int64_t seq, int n) {
  const std::vector<double> fx(static_cast<std::size_t>(n), 1.5), fy(fx.size(), -2.0),
      fz(fx.size(), 0.25);
  const force_block_t m = messaging::to_message({seq * 1000, seq, 50000.0, fx, fy, fz});
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

void set_count(std::vector<std::uint8_t>& bytes, std::int32_t n) {
  const auto u = static_cast<std::uint32_t>(n);
  for (int i = 0; i < 4; ++i) {
    bytes[static_cast<std::size_t>(32 + i)] = static_cast<std::uint8_t>(u >> (24 - 8 * i));
  }
}

TEST(LcmSource, MalformedMessagesAreCountedAndDroppedBeforeDecoding) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  auto queue = std::make_unique<BlockQueue>();
  SourceCounters counters;
  LcmSource source(lcm, "RAW", 100, *queue, counters);
  auto send = [&](const std::vector<std::uint8_t>& bytes) {
    lcm.publish("RAW", bytes.data(), static_cast<unsigned>(bytes.size()));
    EXPECT_EQ(lcm.handleTimeout(1000), 1);
  };

  send(encoded(1, 50));
  auto wrapped = encoded(2, 1);
  set_count(wrapped, 1 + (1 << 29));  // 24 · n wraps a 32-bit length to this one's
  send(wrapped);
  auto huge = encoded(3, 0);
  huge.resize(huge.size() + 8);
  set_count(huge, (1 << 28) + 1);  // 8 · n wraps lcm-gen's int size check
  send(huge);
  auto negative = encoded(4, 3);
  set_count(negative, -1);
  send(negative);
  auto shorter = encoded(5, 10);
  shorter.pop_back();
  send(shorter);
  auto longer = encoded(6, 10);
  longer.push_back(0);
  send(longer);
  send({1, 2, 3});
  auto other_type = encoded(7, 10);
  other_type[0] ^= 0x80;
  send(other_type);
  send(encoded(8, 101));  // whole, but above max_block_samples
  // Its samples are a gap no block has shown yet ...
  EXPECT_EQ(counters.samples_dropped_unseen(), 101);
  send(encoded(9, 100));
  // ... until this one, which carries them (the pipeline's gap before it, or DropLedger).
  EXPECT_EQ(counters.samples_dropped_unseen(), 0);

  EXPECT_EQ(counters.messages.load(), 10);
  EXPECT_EQ(counters.undecodable.load(), 7);
  EXPECT_EQ(counters.oversized.load(), 1);
  EXPECT_EQ(counters.samples_dropped.load(), 101);
  EXPECT_EQ(counters.queue_full.load(), 0);
  // Only the two good blocks arrive, whole.
  auto slot = std::make_unique<BlockSlot>();
  ASSERT_TRUE(queue->try_pop(*slot));
  EXPECT_EQ(slot->seq, 1);
  EXPECT_EQ(slot->count, 50u);
  EXPECT_EQ(slot->fy[49], -2.0);
  ASSERT_TRUE(queue->try_pop(*slot));
  EXPECT_EQ(slot->seq, 9);
  EXPECT_EQ(slot->dropped_before, 101);  // the oversized block's, for the pipeline's gap
  EXPECT_EQ(slot->count, 100u);
  EXPECT_EQ(slot->fz[99], 0.25);
  EXPECT_FALSE(queue->try_pop(*slot));
}

TEST(LcmSource, TheMaximumIsAtMostASlot) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  auto queue = std::make_unique<BlockQueue>();
  SourceCounters counters;
  LcmSource source(lcm, "RAW", 1'000'000, *queue, counters);
  const auto bytes = encoded(1, static_cast<int>(BlockSlot::kMaxSamples) + 1);
  lcm.publish("RAW", bytes.data(), static_cast<unsigned>(bytes.size()));
  EXPECT_EQ(lcm.handleTimeout(1000), 1);
  EXPECT_EQ(counters.oversized.load(), 1);
  auto slot = std::make_unique<BlockSlot>();
  EXPECT_FALSE(queue->try_pop(*slot));
}

// The channel name is longer than a std::string holds in place: the LCM C++ interface's
// per-message std::string of it allocated; the C one, with each block decoded straight into
// the queue's slot, allocates nothing (LCM's own buffers are malloc'ed, not counted here).
TEST(LcmSource, ABlockCostsNoAllocationInSteadyState) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  auto queue = std::make_unique<BlockQueue>();
  SourceCounters counters;
  const std::string channel = "MILLWATCH_FORCE_RAW";
  LcmSource source(lcm, channel, 4096, *queue, counters);
  std::vector<std::vector<std::uint8_t>> blocks;
  for (int k = 0; k < 20; ++k) {
    blocks.push_back(encoded(k, 333));
  }
  auto send = [&](const std::vector<std::uint8_t>& bytes) {
    lcm.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
    ASSERT_EQ(lcm.handleTimeout(1000), 1);
    const BlockSlot* s = queue->front();
    ASSERT_NE(s, nullptr);
    EXPECT_EQ(s->count, 333u);
    queue->pop();
  };
  send(blocks[0]);  // the decoded message's arrays take their size
  const test::AllocationCounter counter;
  for (std::size_t k = 1; k < blocks.size(); ++k) {
    send(blocks[k]);
  }
  EXPECT_EQ(counter.allocations(), 0);
  EXPECT_EQ(counters.messages.load(), 20);
  EXPECT_EQ(counters.samples_dropped.load(), 0);
}

// millwatchd's sample thread handles one message and runs its block before the next: with an LCM
// source's two slots, a burst waits in LCM's subscription queue, not in ours, and nothing is
// lost; the blocks come in order through the same few slots. A queue left full counts the drop.
TEST(LcmSource, TheDaemonsTwoSlotsTakeABurstWhenEachBlockIsRunBeforeTheNext) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  auto queue = std::make_unique<BlockQueue>(LcmSource::kQueueCapacity);
  SourceCounters counters;
  LcmSource source(lcm, "RAW", 4096, *queue, counters);
  constexpr int kBurst = 300;
  for (int k = 0; k < kBurst; ++k) {
    const auto bytes = encoded(k, 333);
    lcm.publish("RAW", bytes.data(), static_cast<unsigned>(bytes.size()));
  }
  std::set<const BlockSlot*> slots;
  std::int64_t expected = 0;
  while (lcm.handleTimeout(0) > 0) {  // as millwatchd's loop: handle, then run what came
    while (const BlockSlot* s = queue->front()) {
      slots.insert(s);
      EXPECT_EQ(s->seq, expected++);
      EXPECT_EQ(s->count, 333u);
      queue->pop();
    }
  }
  EXPECT_EQ(expected, kBurst);
  EXPECT_EQ(counters.messages.load(), kBurst);
  EXPECT_EQ(counters.queue_full.load(), 0);
  EXPECT_EQ(counters.samples_dropped.load(), 0);
  // Every block landed in one of the ring's three slots, round and round.
  EXPECT_EQ(slots.size(), LcmSource::kQueueCapacity + 1);

  // Handled without running the blocks: the third finds both slots taken.
  for (int k = 0; k < 3; ++k) {
    const auto bytes = encoded(kBurst + k, 100);
    lcm.publish("RAW", bytes.data(), static_cast<unsigned>(bytes.size()));
    ASSERT_EQ(lcm.handleTimeout(1000), 1);
  }
  EXPECT_EQ(counters.queue_full.load(), 1);
  EXPECT_EQ(counters.samples_dropped.load(), 100);
  EXPECT_EQ(counters.samples_dropped_unseen(), 100);  // none queued after it
  auto slot = std::make_unique<BlockSlot>();
  ASSERT_TRUE(queue->try_pop(*slot));
  EXPECT_EQ(slot->seq, kBurst);
  ASSERT_TRUE(queue->try_pop(*slot));
  EXPECT_EQ(slot->seq, kBurst + 1);
  EXPECT_FALSE(queue->try_pop(*slot));
}

}  // namespace
}  // namespace millwatch::daemon
