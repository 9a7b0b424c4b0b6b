#pragma once
// Counts heap allocations made by the current thread, so that a test can prove a streaming
// stage allocates nothing in steady state:
//
//   millwatch::test::AllocationCounter counter;
//   stage.process(block);
//   EXPECT_EQ(counter.allocations(), 0);
//
// The global operator new/delete of every test executable are replaced (allocation_counter.cpp)
// to bump a thread-local count. Counting is per thread, so allocations in other threads (gtest,
// loggers) do not disturb the measurement.

#include <cstdint>

namespace millwatch::test {

/// Number of operator-new calls made by this thread since the process started.
std::int64_t thread_allocation_count();

/// Remembers the count at construction; allocations() is the number made since.
class AllocationCounter {
 public:
  AllocationCounter() : start_(thread_allocation_count()) {}
  [[nodiscard]] std::int64_t allocations() const { return thread_allocation_count() - start_; }

 private:
  std::int64_t start_;
};

}  // namespace millwatch::test
