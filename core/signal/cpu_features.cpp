#include "core/signal/cpu_features.hpp"

namespace millwatch::signal {

bool cpu_has_avx() {
#if defined(__x86_64__) || defined(__i386__)
  // libgcc's CPU model: AVX counts only where the OS saves the YMM registers (XGETBV).
  static const bool has_avx = __builtin_cpu_supports("avx") != 0;
  return has_avx;
#else
  return false;
#endif
}

}  // namespace millwatch::signal
