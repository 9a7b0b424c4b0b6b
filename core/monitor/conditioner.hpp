#pragma once
// The pipeline's first signal stage: a checked sample in the instrument's channels becomes the
// filtered force on the tool, re-zeroed.
//
//   axis map (model frame) → low-pass ×3 (causal, or zero-phase offline) → tare
//
// The tare re-zeroes the channels while the tool is quiet (not cutting, and the force envelope
// of the last revolutions well below the usual peak): the force is then zero, and what the
// channels read is the charge amplifiers' offset and drift. The pipeline says when it is
// quiet (set_quiet). Output goes to a callable out(sample, fx, fy, fz), in sample order; in
// zero-phase mode it comes chunk + margin samples late (signal::ZeroPhaseFilter).
// Set up once (allocates); push/flush allocate nothing.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "core/monitor/monitor_config.hpp"
#include "core/signal/axis_map.hpp"
#include "core/signal/butterworth_lowpass.hpp"
#include "core/signal/grid_lowpass.hpp"
#include "core/signal/zero_phase_filter.hpp"

namespace millwatch::monitor {

class Conditioner {
 public:
  Conditioner() = default;
  /// @param filter the design the measurement goes through (the pipeline's, see Pipeline)
  Conditioner(const MonitorConfig& config, const signal::ButterworthDesign& filter);

  /// Ends the current stretch (a gap, the stream's start): held zero-phase samples come out;
  /// the next sample starts a new stretch on which the filters settle.
  template <typename Out>
  void restart(Out&& out) {
    flush(out);
    fresh_ = true;
  }

  /// One checked sample (instrument channels, N) at absolute sample index n. On a grid
  /// (set_stride) it is a block of one sample, and out() hears the grid's samples alone.
  template <typename Out>
  void push(std::int64_t n, const std::array<double, 3>& reading, Out&& out) {
    if (on_grid_) {
      const auto one = [](std::int64_t) { return std::size_t{1}; };
      push_block(n, {&reading[0], 1}, {&reading[1], 1}, {&reading[2], 1}, one,
                 [this, &out](std::int64_t s, std::size_t, const double* x, const double* y,
                              const double* z) {
                   if (s % stride_ == 0) {
                     out(s, *x, *y, *z);
                   }
                 });
      return;
    }
    push_every(n, reading, out);
  }

  /// A block of checked samples (instrument channels, N) from absolute sample index `first`,
  /// handed on in runs: the same output as push() sample by sample, as long as the caller
  /// changes the conditioner's state (set_quiet) only between runs. `run_limit(n)` (≥ 1) is how
  /// many samples from sample n on the caller takes in one run; `out_run(n, count, fx, fy, fz)`
  /// receives them (model frame, filtered, tared; the arrays are the conditioner's scratch,
  /// writable). With a stride (set_stride) only the grid's samples hold values.
  /// The causal filters run over chunks of the block channel-wise
  /// (signal::LowPassFilter::process_three, or signal::GridLowPass on a grid), the tare over
  /// each run.
  template <typename Limit, typename OutRun>
  void push_block(std::int64_t first, std::span<const double> fx, std::span<const double> fy,
                  std::span<const double> fz, Limit&& run_limit, OutRun&& out_run) {
    const std::size_t count = fx.size();
    if (zero_phase_on_) {
      auto out = [&out_run](std::int64_t n, double x, double y, double z) {
        out_run(n, std::size_t{1}, &x, &y, &z);
      };
      for (std::size_t i = 0; i < count; ++i) {
        push_every(first + static_cast<std::int64_t>(i), {fx[i], fy[i], fz[i]}, out);
      }
      return;
    }
    const std::array<const double*, 3> in = {fx.data(), fy.data(), fz.data()};
    const std::array<const double*, 3> source = {in[static_cast<std::size_t>(axis_map_.source[0])],
                                                 in[static_cast<std::size_t>(axis_map_.source[1])],
                                                 in[static_cast<std::size_t>(axis_map_.source[2])]};
    if (on_grid_) {
      push_block_on_grid(first, source, count, run_limit, out_run);
      return;
    }
    for_chunks(first, count, [&](std::size_t from, std::size_t n) {
      if (fresh_) {
        settle_lowpass(axis_map_.to_model({fx[from], fy[from], fz[from]}));
        fresh_ = false;
      }
      // The axis map's signs are applied as the filters read the samples (no pass of their own).
      signal::LowPassFilter::process_three(
          lowpass_, {source[0] + from, source[1] + from, source[2] + from}, axis_map_.sign,
          {chunk_[0].data(), chunk_[1].data(), chunk_[2].data()}, n);
      hand_on(first + static_cast<std::int64_t>(from), n,
              {chunk_[0].data(), chunk_[1].data(), chunk_[2].data()}, run_limit, out_run);
    });
  }

  /// push_block() in two steps for a block whose samples the input check has not tested yet
  /// (InputCheck::check_time): filter_checked() filters it (on the grid, or every sample),
  /// testing every sample against its input channel's limit (InputCheck::sample_limits) in the
  /// filter's own pass — a block read from memory costs the check ~10 % of the pipeline's time
  /// in a pass of its own at 333.3 kHz, ~5 % at 50 kHz, nothing here —, and hands nothing on. True:
  /// every sample was within; hand_on_checked() then hands the block on, as push_block() would have
  /// (the same values, runs and state, bit for bit). False: a sample was not within, or the
  /// block cannot take this way (zero-phase filtering, longer than kCheckedBlock, an axis map
  /// that is not a permutation); the conditioner is as it was, and the caller checks the
  /// samples and calls push_block().
  bool filter_checked(std::int64_t first, std::span<const double> fx, std::span<const double> fy,
                      std::span<const double> fz, const std::array<double, 3>& limit);
  template <typename Limit, typename OutRun>
  void hand_on_checked(Limit&& run_limit, OutRun&& out_run) {
    for_chunks(checked_first_, checked_count_, [&](std::size_t from, std::size_t n) {
      hand_on(checked_first_ + static_cast<std::int64_t>(from), n,
              {checked_[0].data() + from, checked_[1].data() + from, checked_[2].data() + from},
              run_limit, out_run);
    });
    checked_count_ = 0;
  }
  /// The longest block filter_checked() takes.
  static constexpr std::size_t kCheckedBlock = 4096;

  /// Zero-phase mode: every held sample comes out (the end of a stretch or of the record).
  template <typename Out>
  void flush(Out&& out) {
    if (zero_phase_on_) {
      drain(zero_phase_.flush(), out);
    }
  }

  /// Whether the tool is quiet now (not cutting, as far as the pipeline knows), and the usual
  /// peak of the in-plane force while cutting (0: not known yet, no tare).
  void set_quiet(bool quiet, double typical_peak_N) {
    quiet_ = quiet;
    typical_peak_N_ = typical_peak_N;
  }
  [[nodiscard]] const std::array<double, 3>& tare_N() const { return tare_N_; }
  /// The decaying peak of the tared in-plane force's square (what says the tool is quiet), N².
  [[nodiscard]] double envelope_sq_N2() const { return envelope_sq_; }

  /// The caller reads only the samples whose number is a multiple of `stride` (≥ 1): the
  /// pipeline's measuring grid. The causal filters then compute those samples alone
  /// (signal::GridLowPass: the filter's values to rounding), and the envelope and the tare
  /// follow them: the envelope decays over the samples between, the tare's gain is the same
  /// time constant's a grid step. out_run's arrays hold nothing else. (A design GridLowPass
  /// does not run, or zero-phase filtering, filters every sample: while the tare stands, it is
  /// then subtracted on the grid alone.) Call it before the first sample: it starts a stretch.
  void set_stride(int stride);

 private:
  /// push() filtering every sample (the causal filters, or the zero-phase one).
  template <typename Out>
  void push_every(std::int64_t n, const std::array<double, 3>& reading, Out&& out) {
    const auto f = axis_map_.to_model(reading);
    if (zero_phase_on_) {
      if (fresh_) {
        zero_phase_next_ = n;
        fresh_ = false;
      }
      drain(zero_phase_.push(f), out);
      return;
    }
    if (fresh_) {
      settle_lowpass(f);
      fresh_ = false;
    }
    emit(n, lowpass_[0].step(f[0]), lowpass_[1].step(f[1]), lowpass_[2].step(f[2]), out);
  }

  /// A fresh stretch: the causal filters from rest, settled on a sample in the model frame.
  void settle_lowpass(const std::array<double, 3>& model) {
    for (std::size_t a = 0; a < 3; ++a) {
      lowpass_[a].reset();
      lowpass_[a].settle(model[a]);
    }
  }

  /// Calls chunk(from, n) for the chunks of `count` samples from sample `first`: at most kChunk
  /// samples, on a grid ending on it, so that the filter's strides do not straddle them.
  template <typename Chunk>
  void for_chunks(std::int64_t first, std::size_t count, Chunk&& chunk) const {
    const std::int64_t step = on_grid_ ? stride_ : 1;
    for (std::size_t from = 0, n = 0; from < count; from += n) {
      const std::int64_t at_chunk = first + static_cast<std::int64_t>(from);
      const std::int64_t past = at_chunk + static_cast<std::int64_t>(kChunk);
      const std::int64_t end = past - ((past % step) + step) % step;  // the floor
      n = std::min(count - from, static_cast<std::size_t>(end - at_chunk));
      chunk(from, n);
    }
  }

  template <typename Limit, typename OutRun>
  void push_block_on_grid(std::int64_t first, const std::array<const double*, 3>& source,
                          std::size_t count, Limit& run_limit, OutRun& out_run) {
    for_chunks(first, count, [&](std::size_t from, std::size_t n) {
      const std::int64_t at_chunk = first + static_cast<std::int64_t>(from);
      if (fresh_) {
        grid_.settle(at_chunk, {source[0][from], source[1][from], source[2][from]});
        fresh_ = false;
      }
      grid_.process({source[0] + from, source[1] + from, source[2] + from},
                    {chunk_[0].data(), chunk_[1].data(), chunk_[2].data()}, n);
      hand_on(at_chunk, n, {chunk_[0].data(), chunk_[1].data(), chunk_[2].data()}, run_limit,
              out_run);
    });
  }

  /// The chunk's `n` filtered samples from sample `at_chunk` (in `chunk`'s channels: at most
  /// kChunk), tared and handed on in runs.
  template <typename Limit, typename OutRun>
  void hand_on(std::int64_t at_chunk, std::size_t n, const std::array<double*, 3>& chunk,
               Limit& run_limit, OutRun& out_run) {
    for (std::size_t i = 0; i < n;) {
      const std::int64_t at = at_chunk + static_cast<std::int64_t>(i);
      const std::size_t run = std::min(n - i, std::max<std::size_t>(1, run_limit(at)));
      double* x = chunk[0] + i;
      double* y = chunk[1] + i;
      double* z = chunk[2] + i;
      if (on_grid_) {
        tare_run_on_grid(at, x, y, z, run);
      } else {
        tare_run(at, x, y, z, run);
      }
      out_run(at, run, x, y, z);
      i += run;
    }
  }

  /// How many samples from sample `first` the first one on the grid (a multiple of stride_) is.
  [[nodiscard]] std::size_t first_on_grid(std::int64_t first) const {
    const auto behind = static_cast<std::size_t>((first % stride_ + stride_) % stride_);
    return behind == 0 ? 0 : static_cast<std::size_t>(stride_) - behind;
  }

  /// tare_run() for a run filtered on the grid: only its grid samples hold values. The envelope
  /// is e = max(x², e·d) on those, decaying by d a sample over the others (which add nothing);
  /// while quiet, the tare moves at each grid sample by the gain of a grid step.
  void tare_run_on_grid(std::int64_t first, double* fx, double* fy, double* fz, std::size_t count) {
    const auto step = static_cast<std::size_t>(stride_);
    const std::size_t start = first_on_grid(first);
    if (start >= count) {
      envelope_sq_ *= decay_power_[count];
      return;
    }
    if (!(quiet_ && typical_peak_N_ > 0.0)) {  // the tare stands
      tare_standing_on_grid(start, fx, fy, fz, count);
      return;
    }
    const double idle = kIdleFraction * typical_peak_N_;
    double tx = tare_N_[0], ty = tare_N_[1], tz = tare_N_[2];
    double e = envelope_sq_;                 // at the sample before the run
    double decay = decay_power_[start + 1];  // from there to the run's first grid sample
    std::size_t last = start;
    for (std::size_t i = start; i < count; i += step) {
      const double ex = fx[i] - tx;
      const double ey = fy[i] - ty;
      e = std::max(ex * ex + ey * ey, e * decay);
      decay = grid_decay_;
      if (e < idle * idle) {
        tx += grid_tare_gain_ * (fx[i] - tx);
        ty += grid_tare_gain_ * (fy[i] - ty);
        tz += grid_tare_gain_ * (fz[i] - tz);
      }
      fx[i] -= tx;
      fy[i] -= ty;
      fz[i] -= tz;
      last = i;
    }
    envelope_sq_ = e * decay_power_[count - 1 - last];
    tare_N_ = {tx, ty, tz};
  }

  /// tare_run_on_grid() while the tare stands (cutting, or no usual peak yet), from the run's
  /// first grid sample `start`: the envelope's recursion over the grid samples runs as four
  /// interleaved ones (every fourth grid sample, decay D⁴, D a grid step's), joined at the end,
  /// as tare_run() does over every sample — one recursion waits a multiply and a maximum per
  /// grid sample. The same maximum of x_j·D^(age), up to the rounding of the powers of d.
  void tare_standing_on_grid(std::size_t start, double* fx, double* fy, double* fz,
                             std::size_t count) {
    const auto step = static_cast<std::size_t>(stride_);
    const double tx = tare_N_[0], ty = tare_N_[1], tz = tare_N_[2];
    // D^k, k ≤ 4: a chunk holds four grid steps (kChunk ≥ 4·kMaxGridStride).
    const auto grid_power = [&](std::size_t k) { return decay_power_[k * step]; };
    // Grid sample i tared in place; its in-plane square.
    const auto square = [&](std::size_t i) {
      const double ex = fx[i] - tx;
      const double ey = fy[i] - ty;
      fx[i] = ex;
      fy[i] = ey;
      fz[i] -= tz;
      return ex * ex + ey * ey;
    };
    const std::size_t grid_samples = (count - 1 - start) / step + 1;
    const std::size_t whole = grid_samples / 4 * 4;
    double e = 0.0;  // max x_j·D^(age) over the grid samples so far (squares are ≥ 0)
    if (whole > 0) {
      const double d4 = grid_power(4);
      double e0 = 0.0, e1 = 0.0, e2 = 0.0, e3 = 0.0;
      for (std::size_t i = start, end = start + whole * step; i < end; i += 4 * step) {
        e0 = std::max(square(i), e0 * d4);
        e1 = std::max(square(i + step), e1 * d4);
        e2 = std::max(square(i + 2 * step), e2 * d4);
        e3 = std::max(square(i + 3 * step), e3 * d4);
      }
      e = std::max({e0 * grid_power(3), e1 * grid_power(2), e2 * grid_power(1), e3});
    }
    const double d = grid_power(1);
    for (std::size_t i = start + whole * step; i < count; i += step) {
      e = std::max(square(i), e * d);
    }
    // The envelope before the run, decayed to the last grid sample, then to the run's end.
    const std::size_t last = start + (grid_samples - 1) * step;
    e = std::max(e, envelope_sq_ * decay_power_[start + 1] * decay_power_[last - start]);
    envelope_sq_ = e * decay_power_[count - 1 - last];
  }

  template <typename Out>
  void drain(std::size_t ready, Out& out) {
    for (std::size_t k = 0; k < ready; ++k) {
      emit(zero_phase_next_ + static_cast<std::int64_t>(k), zero_phase_.output(0, k),
           zero_phase_.output(1, k), zero_phase_.output(2, k), out);
    }
    zero_phase_next_ += static_cast<std::int64_t>(ready);
  }

  /// emit()'s tare over a run of samples from sample `first`, in place (while the tare stands,
  /// subtracted from the samples the caller reads alone: set_stride()).
  void tare_run(std::int64_t first, double* fx, double* fy, double* fz, std::size_t count) {
    if (quiet_ && typical_peak_N_ > 0.0) {  // the tare may move: sample by sample
      for (std::size_t i = 0; i < count; ++i) {
        emit(0, fx[i], fy[i], fz[i], [&](std::int64_t, double x, double y, double z) {
          fx[i] = x;
          fy[i] = y;
          fz[i] = z;
        });
      }
      return;
    }
    // Cutting (or no usual peak yet): the tare stands; only the envelope moves. Its recursion
    // e = max(x, e·d) runs as four interleaved ones (every fourth sample, decay d⁴), joined at
    // the end: the same maximum of x_j·d^(age), up to the rounding of the powers of d.
    const double tx = tare_N_[0], ty = tare_N_[1], tz = tare_N_[2];
    const auto square = [&](std::size_t i) {
      const double ex = fx[i] - tx;
      const double ey = fy[i] - ty;
      return ex * ex + ey * ey;
    };
    const std::size_t whole = count / 4 * 4;  // count ≤ kChunk
    double envelope_sq = envelope_sq_ * decay_power_[whole];
    if (whole > 0) {
      const double d4 = decay_power_[4];
      double e0 = 0.0, e1 = 0.0, e2 = 0.0, e3 = 0.0;
#if defined(__SSE2__)
      // The four recursions as two SSE2 pairs (e0, e1) and (e2, e3): maxpd(e·d⁴, x²) is
      // (e·d⁴ > x²) ? e·d⁴ : x², which is std::max(x², e·d⁴), NaN and zeros alike.
      const __m128d t_x = _mm_set1_pd(tx), t_y = _mm_set1_pd(ty), d = _mm_set1_pd(d4);
      __m128d e01 = _mm_setzero_pd(), e23 = _mm_setzero_pd();
      const auto pair = [&](std::size_t i) {
        const __m128d ex = _mm_sub_pd(_mm_loadu_pd(fx + i), t_x);
        const __m128d ey = _mm_sub_pd(_mm_loadu_pd(fy + i), t_y);
        return _mm_add_pd(_mm_mul_pd(ex, ex), _mm_mul_pd(ey, ey));
      };
      for (std::size_t i = 0; i < whole; i += 4) {
        e01 = _mm_max_pd(_mm_mul_pd(e01, d), pair(i));
        e23 = _mm_max_pd(_mm_mul_pd(e23, d), pair(i + 2));
      }
      e0 = _mm_cvtsd_f64(e01);
      e1 = _mm_cvtsd_f64(_mm_unpackhi_pd(e01, e01));
      e2 = _mm_cvtsd_f64(e23);
      e3 = _mm_cvtsd_f64(_mm_unpackhi_pd(e23, e23));
#else
      for (std::size_t i = 0; i < whole; i += 4) {
        e0 = std::max(square(i), e0 * d4);
        e1 = std::max(square(i + 1), e1 * d4);
        e2 = std::max(square(i + 2), e2 * d4);
        e3 = std::max(square(i + 3), e3 * d4);
      }
#endif
      envelope_sq = std::max(
          {envelope_sq, e0 * decay_power_[3], e1 * decay_power_[2], e2 * decay_power_[1], e3});
    }
    for (std::size_t i = whole; i < count; ++i) {
      envelope_sq = std::max(square(i), envelope_sq * envelope_decay_);
    }
    envelope_sq_ = envelope_sq;
    // The first sample of the run on the caller's grid.
    const auto step = static_cast<std::size_t>(stride_);
    if (step == 1) {
      // A channel at a time: one loop over three arrays that may alias (for all the compiler
      // knows) stays scalar; each of these is vectorised.
      const auto subtract = [count](double* v, double tare) {
        for (std::size_t i = 0; i < count; ++i) {
          v[i] -= tare;
        }
      };
      subtract(fx, tx);
      subtract(fy, ty);
      subtract(fz, tz);
      return;
    }
    for (std::size_t i = first_on_grid(first); i < count; i += step) {
      fx[i] -= tx;
      fy[i] -= ty;
      fz[i] -= tz;
    }
  }

  template <typename Out>
  void emit(std::int64_t n, double fx, double fy, double fz, Out&& out) {
    const double ex = fx - tare_N_[0];
    const double ey = fy - tare_N_[1];
    envelope_sq_ = std::max(ex * ex + ey * ey, envelope_sq_ * envelope_decay_);
    const double idle = kIdleFraction * typical_peak_N_;
    if (quiet_ && typical_peak_N_ > 0.0 && envelope_sq_ < idle * idle) {
      tare_N_[0] += tare_gain_ * (fx - tare_N_[0]);
      tare_N_[1] += tare_gain_ * (fy - tare_N_[1]);
      tare_N_[2] += tare_gain_ * (fz - tare_N_[2]);
    }
    out(n, fx - tare_N_[0], fy - tare_N_[1], fz - tare_N_[2]);
  }

  static constexpr double kIdleFraction = 0.2;  // of the usual peak: a quiet envelope
  static constexpr std::size_t kChunk = 256;    // samples filtered at a time by push_block()
  // A chunk on a grid ends on it, and decay_power_ holds four grid steps' decay
  // (tare_standing_on_grid's D⁴).
  static_assert(kChunk >= 4 * static_cast<std::size_t>(signal::kMaxGridStride));

  signal::AxisMap axis_map_;
  std::array<signal::LowPassFilter, 3> lowpass_;
  std::array<std::array<double, kChunk>, 3> chunk_{};  // push_block()'s channels in the model frame
  signal::ZeroPhaseFilter zero_phase_;
  bool zero_phase_on_ = false;
  std::int64_t zero_phase_next_ = 0;  // sample number of its next output
  bool fresh_ = true;
  std::array<double, 3> tare_N_{};
  double tare_gain_ = 0.0;
  double envelope_sq_ = 0.0;  // decaying peak of the squared in-plane force, N²
  double envelope_decay_ = 0.0;
  std::array<double, kChunk + 1> decay_power_{};  // envelope_decay_^k
  bool quiet_ = false;
  double typical_peak_N_ = 0.0;
  int stride_ = 1;            // push_block()'s caller reads every stride_-th sample (set_stride)
  signal::GridLowPass grid_;  // push_block()'s filters on the grid (set_stride)
  bool on_grid_ = false;
  double grid_decay_ = 1.0;      // envelope_decay_^stride_
  double grid_tare_gain_ = 0.0;  // 1 − (1 − tare_gain_)^stride_
  // filter_checked()'s block, filtered (kCheckedBlock per channel, allocated when set up), from
  // sample checked_first_, checked_count_ samples not yet handed on.
  std::array<std::vector<double>, 3> checked_;
  std::int64_t checked_first_ = 0;
  std::size_t checked_count_ = 0;
};

}  // namespace millwatch::monitor
