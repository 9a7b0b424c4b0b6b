#pragma once
// Sample blocks handed from a source's thread to the sample thread: fixed-size slots in a
// bounded single-producer single-consumer ring, filled and read in place, so that neither side
// allocates or copies a block through the queue: the source decodes or converts straight into
// the free slot (claim, fill, publish), the sample thread runs the pipeline on the oldest slot
// where it lies (front, process, pop). A full ring refuses the block and the source counts it.
// The sample thread sleeps in wait() until a block is published (or a timeout: it has a status
// and a watchdog to keep), instead of polling. The capacity is the source's: a reader thread
// (Comedi) needs room for a backlog; an LCM source decodes in the sample thread itself, one block
// at a time, and a few slots, used again and again, stay in the cache where 64 slots of 98 KB
// (6.4 MB, each touched once every 65 blocks) came back cold for every block.
//
//   producer: if (BlockSlot* s = q.claim()) { fill(*s); q.publish(); } else count_drop();
//   consumer: if (const BlockSlot* s = q.front()) { use(s->view()); q.pop(); } else q.wait(t);

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>

#include "core/monitor/sample_block.hpp"

namespace millwatch::daemon {

struct BlockSlot {
  static constexpr std::size_t kMaxSamples = 4096;
  std::int64_t utime_us = 0;
  std::int64_t seq = 0;
  double sample_rate_hz = 0.0;
  std::size_t count = 0;
  /// Samples the source dropped since the block before (SourceCounters::queuing_block()).
  std::int64_t dropped_before = 0;
  std::array<double, kMaxSamples> fx{}, fy{}, fz{};

  /// Sets the header (nothing dropped before) and copies the first `n` (≤ kMaxSamples) samples
  /// of each axis.
  void assign(std::int64_t utime, std::int64_t sequence, double rate_hz, const double* x,
              const double* y, const double* z, std::size_t n) {
    dropped_before = 0;
    utime_us = utime;
    seq = sequence;
    sample_rate_hz = rate_hz;
    count = std::min(n, kMaxSamples);
    std::copy_n(x, count, fx.begin());
    std::copy_n(y, count, fy.begin());
    std::copy_n(z, count, fz.begin());
  }

  [[nodiscard]] monitor::SampleBlock view() const {
    return {utime_us,          seq, sample_rate_hz, {fx.data(), count}, {fy.data(), count},
            {fz.data(), count}};
  }
};

class BlockQueue {
 public:
  /// A reader thread's backlog: 64 blocks (at 333.3 kHz in 1 ms blocks, 64 ms).
  static constexpr std::size_t kCapacity = 64;

  /// Room for `capacity` blocks (at least 1), 98 KB each, on the heap.
  explicit BlockQueue(std::size_t capacity = kCapacity)
      : size_(std::max<std::size_t>(capacity, 1) + 1),
        slots_(std::make_unique<BlockSlot[]>(size_)) {}
  [[nodiscard]] std::size_t capacity() const { return size_ - 1; }

  // Producer side.
  /// The next free slot to fill, or null when the ring is full. Valid until publish().
  BlockSlot* claim() {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (next(head) == tail_.load(std::memory_order_acquire)) {
      return nullptr;
    }
    return &slots_[head];
  }
  /// Hands the claimed slot to the consumer and wakes it.
  void publish() {
    head_.store(next(head_.load(std::memory_order_relaxed)), std::memory_order_release);
    // Taken and released so that a consumer between its check and its sleep cannot miss this.
    { const std::lock_guard lock(mutex_); }
    ready_.notify_one();
  }
  /// claim(), copy, publish(); false (nothing kept) when full.
  bool try_push(const BlockSlot& block) {
    BlockSlot* s = claim();
    if (s == nullptr) {
      return false;
    }
    s->assign(block.utime_us, block.seq, block.sample_rate_hz, block.fx.data(), block.fy.data(),
              block.fz.data(), block.count);
    s->dropped_before = block.dropped_before;
    publish();
    return true;
  }

  // Consumer side.
  /// The oldest block, or null when the ring is empty. Valid until pop().
  [[nodiscard]] const BlockSlot* front() const {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    return tail == head_.load(std::memory_order_acquire) ? nullptr : &slots_[tail];
  }
  /// Releases the block front() gave.
  void pop() {
    tail_.store(next(tail_.load(std::memory_order_relaxed)), std::memory_order_release);
  }
  /// front(), copy, pop(); false when empty.
  bool try_pop(BlockSlot& out) {
    const BlockSlot* s = front();
    if (s == nullptr) {
      return false;
    }
    out.assign(s->utime_us, s->seq, s->sample_rate_hz, s->fx.data(), s->fy.data(), s->fz.data(),
               s->count);
    out.dropped_before = s->dropped_before;
    pop();
    return true;
  }
  /// Sleeps until a block is published or `timeout` has passed; true when one is waiting.
  bool wait(std::chrono::microseconds timeout) {
    std::unique_lock lock(mutex_);
    return ready_.wait_for(lock, timeout, [this] { return front() != nullptr; });
  }
  [[nodiscard]] bool empty() const { return front() == nullptr; }

 private:
  [[nodiscard]] std::size_t next(std::size_t i) const { return i + 1 == size_ ? 0 : i + 1; }

  const std::size_t size_;  // slots: the capacity and one kept free to tell full from empty
  std::unique_ptr<BlockSlot[]> slots_;
  alignas(64) std::atomic<std::size_t> head_{0};
  alignas(64) std::atomic<std::size_t> tail_{0};
  std::mutex mutex_;
  std::condition_variable ready_;
};

}  // namespace millwatch::daemon
