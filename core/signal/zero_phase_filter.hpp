#pragma once
// Zero-phase low-pass filtering of a stream, for offline work (replay of a recorded cut).
//
// filtfilt() needs the whole record; a recording of minutes at 333 kHz need not fit in memory.
// This stage runs the forward pass continuously and the backward pass over chunks: to emit the
// `chunk` oldest held samples it filters backwards from `margin` samples beyond them, starting
// from the steady state of the newest forward output. The start-up error of that backward pass
// decays like the slowest pole, r^margin; margin_samples() makes it < 10⁻¹² of the signal, so the
// output equals filtfilt's (magnitude |H|², no phase, no delay; both ends of a stretch padded
// by odd reflection as filtfilt does). The price is latency: up to chunk + margin samples are
// held.
//
// Several channels share the timing. Set up once (allocates), then push() sample by sample
// without allocating; flush() at the end of a stretch (a gap, the end of the record).

#include <cstddef>
#include <span>
#include <vector>

#include "core/signal/butterworth_lowpass.hpp"

namespace millwatch::signal {

class ZeroPhaseFilter {
 public:
  /// No channels: push() rejects everything until set up.
  ZeroPhaseFilter() = default;
  /// @param chunk_samples samples emitted per backward pass (≥ 1); 0 picks 4·margin, at least 4096.
  /// @throws std::invalid_argument for channels < 1.
  ZeroPhaseFilter(const ButterworthDesign& design, int channels, std::size_t chunk_samples = 0);

  /// Backward-pass run-in after which the start-up error is below 10⁻¹² (slowest pole radius r:
  /// ⌈ln 10⁻¹² / ln r⌉ samples).
  [[nodiscard]] static std::size_t margin_samples(const ButterworthDesign& design);

  /// Adds one sample of every channel (x.size() == channels()). Returns how many filtered samples
  /// are ready (0 or chunk_samples()); they are output(c, 0..ready) until the next push or flush.
  /// @throws std::invalid_argument on a size mismatch (a programming error).
  std::size_t push(std::span<const double> x);
  /// Ends the stretch: every held sample becomes ready; the next push starts a new stretch.
  std::size_t flush();

  /// Filtered sample i (oldest first) of channel c among the ready ones.
  [[nodiscard]] double output(int channel, std::size_t i) const {
    return out_[static_cast<std::size_t>(channel)][i];
  }
  [[nodiscard]] std::size_t held() const { return held_; }
  [[nodiscard]] int channels() const { return static_cast<int>(forward_.size()); }
  [[nodiscard]] std::size_t chunk_samples() const { return chunk_; }
  [[nodiscard]] std::size_t margin() const { return margin_; }

 private:
  /// Backward pass over the held samples; the oldest `count` become ready.
  std::size_t emit(std::size_t count);
  /// Starts the forward pass of a stretch on its first `count` inputs (held in recent_in_).
  void start_forward(std::size_t count);

  ButterworthDesign design_;
  std::size_t chunk_ = 0;
  std::size_t margin_ = 0;
  std::size_t pad_ = 0;              ///< odd-reflection length at the end of a stretch
  std::size_t held_ = 0;             ///< forward-filtered samples not yet emitted, per channel
  std::size_t stretch_samples_ = 0;  ///< inputs since the stretch began
  std::vector<LowPassFilter> forward_;
  std::vector<std::vector<double>> forward_out_;  ///< chunk + margin held samples per channel
  std::vector<std::vector<double>> out_;          ///< ready samples per channel
  std::vector<std::vector<double>> recent_in_;    ///< ring of the last pad + 1 inputs
};

}  // namespace millwatch::signal
