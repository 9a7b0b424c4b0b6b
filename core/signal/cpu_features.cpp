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

bool cpu_has_fma() {
#if defined(__x86_64__) || defined(__i386__)
  static const bool has_fma =
      cpu_has_avx() && __builtin_cpu_supports("avx2") != 0 && __builtin_cpu_supports("fma") != 0;
  return has_fma;
#else
  return false;
#endif
}

bool cpu_has_avx512vl() {
#if defined(__x86_64__) || defined(__i386__)
  // libgcc counts AVX-512 only where the OS saves the ZMM and mask registers (XGETBV).
  static const bool has_avx512vl = cpu_has_fma() && __builtin_cpu_supports("avx512f") != 0 &&
                                   __builtin_cpu_supports("avx512vl") != 0 &&
                                   __builtin_cpu_supports("avx512dq") != 0;
  return has_avx512vl;
#else
  return false;
#endif
}

}  // namespace millwatch::signal
