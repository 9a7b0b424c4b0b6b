// millwatchd's block queue: blocks are filled and read in place in its slots, in order, a full
// ring refuses (the source counts the drop), and the sample thread asleep in wait() wakes when a
// block is published from another thread — and times out when none is.

#include "daemon/block_queue.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <memory>
#include <thread>

namespace millwatch::daemon {
namespace {

TEST(BlockQueue, BlocksAreFilledAndReadInPlaceInOrderAndAFullRingRefuses) {
  // The reader thread's 64 slots, an LCM source's 2, and the least there can be; filled and
  // drained three times, so that the ring wraps.
  for (const std::size_t capacity : {BlockQueue::kCapacity, std::size_t{2}, std::size_t{1}}) {
    auto q = std::make_unique<BlockQueue>(capacity);
    ASSERT_EQ(q->capacity(), capacity);
    std::int64_t seq = 0;
    for (int round = 0; round < 3; ++round) {
      EXPECT_TRUE(q->empty());
      EXPECT_EQ(q->front(), nullptr);
      for (std::size_t k = 0; k < capacity; ++k) {
        BlockSlot* s = q->claim();
        ASSERT_NE(s, nullptr) << capacity << " " << k;
        const double x[] = {static_cast<double>(seq + static_cast<std::int64_t>(k)), 1.0};
        const double y[] = {2.0, 3.0}, z[] = {4.0, -5.0};
        s->assign(1000 * (seq + static_cast<std::int64_t>(k)), seq + static_cast<std::int64_t>(k),
                  50000.0, x, y, z, 2);
        q->publish();
      }
      EXPECT_EQ(q->claim(), nullptr) << capacity;  // full: the source drops and counts the block
      for (std::size_t k = 0; k < capacity; ++k, ++seq) {
        const BlockSlot* s = q->front();
        ASSERT_NE(s, nullptr) << capacity << " " << k;
        const monitor::SampleBlock b = s->view();
        EXPECT_EQ(b.seq, seq);
        EXPECT_EQ(b.utime_us, 1000 * seq);
        ASSERT_EQ(b.fx_N.size(), 2u);
        EXPECT_EQ(b.fx_N[0], static_cast<double>(seq));
        EXPECT_EQ(b.fz_N[1], -5.0);
        EXPECT_EQ(b.fx_N.data(), s->fx.data());  // the slot itself, not a copy
        q->pop();
        if (k == 0) {
          EXPECT_NE(q->claim(), nullptr);  // one slot free again
        }
      }
    }
    EXPECT_TRUE(q->empty());
  }
}

TEST(BlockQueue, TheConsumerSleepsUntilABlockIsPublished) {
  auto q = std::make_unique<BlockQueue>();
  EXPECT_FALSE(q->wait(std::chrono::milliseconds(1)));  // nothing: times out
  constexpr int kBlocks = 2000;
  std::thread producer([&] {
    BlockSlot block;
    block.count = 333;
    for (int k = 0; k < kBlocks; ++k) {
      block.seq = k;
      block.dropped_before = k % 3;  // each slot's own, never a stale one from its last trip
      block.fy[332] = k;
      while (!q->try_push(block)) {
        std::this_thread::yield();  // the consumer is behind: the test loses nothing
      }
      if (k % 100 == 0) {
        std::this_thread::sleep_for(std::chrono::microseconds(200));  // the consumer sleeps
      }
    }
  });
  int received = 0;
  while (received < kBlocks) {
    if (const BlockSlot* s = q->front()) {
      EXPECT_EQ(s->seq, received);
      EXPECT_EQ(s->dropped_before, received % 3);
      EXPECT_EQ(s->count, 333u);
      EXPECT_EQ(s->fy[332], received);
      q->pop();
      ++received;
      continue;
    }
    // A lost wake-up would stall the test here for the whole timeout, again and again.
    q->wait(std::chrono::seconds(10));
  }
  producer.join();
  EXPECT_TRUE(q->empty());
}

}  // namespace
}  // namespace millwatch::daemon
