#pragma once
// An allocator whose blocks start on a cache line (64 bytes). A std::vector<double> of a few
// hundred kilobytes otherwise starts 16 bytes past a page (glibc's mmap'd blocks), and rows of
// 32 bytes laid from there straddle two cache lines every other row: each SIMD load or store of
// such a row is split in two.

#include <cstddef>
#include <new>
#include <vector>

namespace millwatch::monitor {

template <typename T>
struct CacheAligned {
  using value_type = T;
  static constexpr std::align_val_t kAlignment{64};

  CacheAligned() = default;
  template <typename U>
  CacheAligned(const CacheAligned<U>& /*other*/) {}  // NOLINT(google-explicit-constructor)

  T* allocate(std::size_t n) { return static_cast<T*>(::operator new(n * sizeof(T), kAlignment)); }
  void deallocate(T* p, std::size_t /*n*/) { ::operator delete(p, kAlignment); }

  template <typename U>
  bool operator==(const CacheAligned<U>& /*other*/) const {
    return true;
  }
};

/// A vector whose first element starts a cache line.
template <typename T>
using CacheAlignedVector = std::vector<T, CacheAligned<T>>;

}  // namespace millwatch::monitor
