#pragma once
// What the processor running us can do, for the few kernels compiled for more than x86-64's
// baseline (each alone, with a target attribute): they run only where the check says so, and the
// package runs on any x86-64.

namespace millwatch::signal {

/// Whether this CPU (and its operating system: the YMM registers are saved) runs AVX code.
[[nodiscard]] bool cpu_has_avx();
/// Whether it runs AVX2 and FMA3 code (and AVX: the YMM registers are saved).
[[nodiscard]] bool cpu_has_fma();
/// Whether it runs AVX-512F, VL and DQ code (the OS saving the ZMM registers), with FMA.
[[nodiscard]] bool cpu_has_avx512vl();

}  // namespace millwatch::signal
