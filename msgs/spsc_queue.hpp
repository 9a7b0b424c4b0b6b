#pragma once
// A bounded single-producer single-consumer queue: the sample thread pushes without blocking or
// allocating (a full queue refuses and the caller counts the drop), one consumer thread pops.

#include <array>
#include <atomic>
#include <cstddef>
#include <optional>

namespace millwatch::messaging {

template <typename T, std::size_t Capacity>
class SpscQueue {
 public:
  /// Producer side. Returns false (and keeps nothing) when the queue is full.
  bool try_push(const T& item) {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    const std::size_t next = (head + 1) % (Capacity + 1);
    if (next == tail_.load(std::memory_order_acquire)) {
      return false;
    }
    slots_[head] = item;
    head_.store(next, std::memory_order_release);
    return true;
  }
  /// Consumer side: copies the oldest item into `out`; false when empty.
  bool try_pop(T& out) {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_.load(std::memory_order_acquire)) {
      return false;
    }
    out = slots_[tail];
    tail_.store((tail + 1) % (Capacity + 1), std::memory_order_release);
    return true;
  }
  [[nodiscard]] bool empty() const {
    return tail_.load(std::memory_order_acquire) == head_.load(std::memory_order_acquire);
  }

 private:
  std::array<T, Capacity + 1> slots_{};
  alignas(64) std::atomic<std::size_t> head_{0};
  alignas(64) std::atomic<std::size_t> tail_{0};
};

}  // namespace millwatch::messaging
