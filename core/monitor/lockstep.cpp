#include "core/monitor/lockstep.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <complex>
#include <cstdint>
#include <numbers>
#include <utility>

#include "core/monitor/extremum.hpp"
#include "core/monitor/grid_line.hpp"
#include "core/signal/cpu_features.hpp"

#if defined(__SSE2__) && defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#define MILLWATCH_LOCKSTEP_AVX 1
#include <immintrin.h>
#endif

namespace millwatch::monitor {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

double wrap_2pi(double a) {
  a = std::fmod(a, kTwoPi);
  return a < 0.0 ? a + kTwoPi : a;
}

}  // namespace

Lockstep::Lockstep(const model::ModelConfig& model, const signal::ButterworthDesign& filter,
                   bool zero_phase)
    : commanded_(model),
      config_(model),
      filter_(filter),
      zero_phase_(zero_phase),
      workspace_(model, model.resolution.steps_per_rev),
      response_(model.resolution.steps_per_rev) {
  const auto steps = static_cast<std::size_t>(model.resolution.steps_per_rev);
  for (auto* axis : {&waveform_.fx_N, &waveform_.fy_N, &waveform_.fz_N}) {
    axis->assign(steps, 0.0);
  }
  for (auto& f : filtered_) {
    f.assign(steps, 0.0);
  }
  line_table_.assign(steps, LineRow{});
}

bool Lockstep::set_spindle_hz(double spindle_hz) {
  if (built_ && std::fabs(spindle_hz - spindle_hz_) <= 0.002 * spindle_hz_) {
    return false;
  }
  spindle_hz_ = spindle_hz;
  const double rpm = 60.0 * spindle_hz;
  // The feed rate is what the control commands: a faster spindle cuts thinner chips.
  model::at_actual_speed(commanded_, rpm, config_);
  const int steps = commanded_.resolution.steps_per_rev;
  const model::SteadyState& s = model::evaluate_steady_state(config_, rpm, steps, workspace_,
                                                             model::SteadyStateOutput::kMean);
  stats_ = s.stats;
  std::copy(s.mean.fx_N.begin(), s.mean.fx_N.end(), waveform_.fx_N.begin());
  std::copy(s.mean.fy_N.begin(), s.mean.fy_N.end(), waveform_.fy_N.begin());
  std::copy(s.mean.fz_N.begin(), s.mean.fz_N.end(), waveform_.fz_N.begin());
  filter_periodic();
  built_ = true;
  revise();
  return true;
}

void Lockstep::build(const model::ModelConfig& commanded, double spindle_hz) {
  commanded_ = commanded;
  built_ = false;
  set_spindle_hz(spindle_hz);
}

void Lockstep::take_model(Lockstep& built) {
  std::swap(commanded_, built.commanded_);
  std::swap(config_, built.config_);
  std::swap(waveform_, built.waveform_);
  std::swap(filtered_, built.filtered_);
  std::swap(line_table_, built.line_table_);
  std::swap(stats_, built.stats_);
  std::swap(spindle_hz_, built.spindle_hz_);
  std::swap(built_, built.built_);
  aligned_ = aligned_ && built_;
  revise();
  built.revise();
}

void Lockstep::revise() {
  // One sequence for every object: a revision names one model and alignment in the process.
  static std::atomic<std::uint64_t> last{0};
  revision_ = last.fetch_add(1, std::memory_order_relaxed) + 1;
}

void Lockstep::set_alignment(double alignment_rad) {
  offset_rad_ = wrap_2pi(alignment_rad);
  aligned_ = built_;
  revise();
}

void Lockstep::filter_periodic() {
  // The causal filter's steady state on the periodic model force (or |H|² for forwards and
  // backwards): each harmonic k of the spindle frequency times H(k·f).
  const auto response = [this](double hz) { return filter_.response(hz); };
  const model::ResponseUse use =
      zero_phase_ ? model::ResponseUse::kPower : model::ResponseUse::kComplex;
  const std::array<const std::vector<double>*, 3> in = {&waveform_.fx_N, &waveform_.fy_N,
                                                        &waveform_.fz_N};
  for (std::size_t a = 0; a < 3; ++a) {
    std::copy(in[a]->begin(), in[a]->end(), filtered_[a].begin());
    response_.apply(filtered_[a], spindle_hz_, response, use);
  }
  // forces_on_line()'s table: per grid point the three values and the steps to the next point.
  const std::size_t n = filtered_[0].size();
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t k1 = k + 1 == n ? 0 : k + 1;
    auto& row = line_table_[k].v;
    for (std::size_t a = 0; a < 3; ++a) {
      row[a] = filtered_[a][k];
      row[4 + a] = filtered_[a][k1] - filtered_[a][k];
    }
  }
}

void Lockstep::filtered_on_tracker_grid(int axis, int bins, std::vector<double>& out) const {
  out.resize(static_cast<std::size_t>(bins));
  const auto& w = filtered_[static_cast<std::size_t>(axis)];
  const auto n = static_cast<double>(w.size());
  for (int b = 0; b < bins; ++b) {
    const double model_angle = wrap_2pi(kTwoPi * b / bins + offset_rad_);
    const double pos = model_angle / kTwoPi * n;
    const auto k0 = static_cast<std::size_t>(pos) % w.size();
    const std::size_t k1 = (k0 + 1) % w.size();
    const double f = pos - std::floor(pos);
    out[static_cast<std::size_t>(b)] = w[k0] + f * (w[k1] - w[k0]);
  }
}

bool Lockstep::align(const SyncAverage& measured) {
  if (!built_ || measured.revolutions() == 0) {
    return false;
  }
  const int bins = measured.bins();
  const auto ub = static_cast<std::size_t>(bins);
  // Model filtered waveform at zero offset on the tracker grid, and the measured average.
  const double saved = offset_rad_;
  offset_rad_ = 0.0;
  for (int a = 0; a < 3; ++a) {
    auto& model = model_bins_[static_cast<std::size_t>(a)];
    auto& meas = measured_bins_[static_cast<std::size_t>(a)];
    filtered_on_tracker_grid(a, bins, model);
    measured.average(a, meas);
    // Means removed: drift and offsets are not shape.
    for (auto* v : {&model, &meas}) {
      double mean = 0.0;
      for (double x : *v) {
        mean += x;
      }
      mean /= bins;
      for (double& x : *v) {
        x -= mean;
      }
    }
  }
  offset_rad_ = saved;
  // Circular correlation c(s) = Σ_axes Σ_b meas[b]·model[b + s]: the model shifted by s bins.
  std::vector<double>& corr = correlation_scratch_;
  corr.assign(ub, 0.0);
  double norm_m = 0.0, norm_d = 0.0;
  for (std::size_t a = 0; a < 3; ++a) {
    const auto& m = measured_bins_[a];
    const auto& d = model_bins_[a];
    for (std::size_t b = 0; b < ub; ++b) {
      norm_m += m[b] * m[b];
      norm_d += d[b] * d[b];
    }
    for (std::size_t sh = 0; sh < ub; ++sh) {
      // Σ_b m[b]·d[(b + sh) mod B] in two runs, without a modulo per term (same order of terms).
      double c = 0.0;
      const std::size_t wrap = ub - sh;
      for (std::size_t b = 0; b < wrap; ++b) {
        c += m[b] * d[b + sh];
      }
      for (std::size_t b = wrap; b < ub; ++b) {
        c += m[b] * d[b - wrap];
      }
      corr[sh] += c;
    }
  }
  std::size_t best = 0;
  for (std::size_t sh = 1; sh < ub; ++sh) {
    if (corr[sh] > corr[best]) {
      best = sh;
    }
  }
  const Extremum e = refine_extremum(
      [&](std::int64_t sh) { return corr[static_cast<std::size_t>(((sh % bins) + bins) % bins)]; },
      static_cast<std::int64_t>(best), 1, false);
  offset_rad_ = wrap_2pi(kTwoPi * e.position / bins);
  correlation_ = corr[best] / std::sqrt(std::max(norm_m * norm_d, 1e-300));
  aligned_ = true;
  revise();
  return true;
}

std::array<double, 3> Lockstep::force_at(double tracker_angle_rad) const {
  const double turns = (tracker_angle_rad + offset_rad_) / kTwoPi;
  const std::size_t n = filtered_[0].size();
  const double pos = (turns - std::floor(turns)) * static_cast<double>(n);
  const auto k0 = std::min(static_cast<std::size_t>(pos), n - 1);
  const std::size_t k1 = k0 + 1 == n ? 0 : k0 + 1;
  const double f = pos - static_cast<double>(k0);
  return {filtered_[0][k0] + f * (filtered_[0][k1] - filtered_[0][k0]),
          filtered_[1][k0] + f * (filtered_[1][k1] - filtered_[1][k0]),
          filtered_[2][k0] + f * (filtered_[2][k1] - filtered_[2][k0])};
}

namespace {

/// The grid point at or below a position in [0, n] (at most the last point, n − 1) and the
/// fraction past it. Signed indices: a double converts to a signed integer in one instruction
/// (to an unsigned one only through a test and two paths); positions are far below 2⁶³.
[[gnu::always_inline]] inline std::int64_t grid_point(double pos, std::int64_t last_point,
                                                      double& fraction) {
  const std::int64_t k0 = std::min(static_cast<std::int64_t>(pos), last_point);
  fraction = pos - static_cast<double>(k0);
  return k0;
}

/// Rows fx, fy, fz, fx² + fy² along the line of grid positions: w[k0] + f·(w[k0 + 1] − w[k0])
/// from one row of the line table (values, 0, steps, 0).
void line_rows_scalar(const Lockstep::LineRow* table, GridLine line, std::int64_t last_point,
                      std::int64_t samples, double* rows) {
  for (std::int64_t i = 0; i < samples; ++i) {
    double f = 0.0;
    const double* t = table[grid_point(line.at(i), last_point, f)].v.data();
    const double fx = t[0] + f * t[4];
    const double fy = t[1] + f * t[5];
    double* r = rows + 4 * i;
    r[0] = fx;
    r[1] = fy;
    r[2] = t[2] + f * t[6];
    r[3] = fx * fx + fy * fy;
  }
}

#if defined(MILLWATCH_LOCKSTEP_AVX)
/// line_rows_scalar() with a table row's values and steps each one 256-bit load, the three
/// forces one multiply and one add: the same operations on each lane, so the same rows, bit
/// for bit. The row's fourth value, fx² + fy², is stored over the padding lane.
__attribute__((target("avx"))) void line_rows_avx(const Lockstep::LineRow* table, GridLine line,
                                                  std::int64_t last_point, std::int64_t samples,
                                                  double* rows) {
  const auto count = static_cast<std::size_t>(samples);
  GridChunk chunk;  // the samples' grid points and fractions, four at a time
  for (std::size_t from = 0; from < count; from += kGridChunk) {
    const std::size_t n = std::min(kGridChunk, count - from);
    grid_chunk_avx(line, from, n, static_cast<std::int32_t>(last_point), chunk);
    for (std::size_t j = 0; j < n; ++j) {
      const double* t = table[chunk.point[j]].v.data();
      const __m256d forces = _mm256_add_pd(
          _mm256_loadu_pd(t),
          _mm256_mul_pd(_mm256_broadcast_sd(&chunk.fraction[j]), _mm256_loadu_pd(t + 4)));
      const __m128d xy = _mm256_castpd256_pd128(forces);
      const __m128d xy2 = _mm_mul_pd(xy, xy);
      double* r = rows + 4 * (from + j);
      _mm256_storeu_pd(r, forces);
      _mm_store_sd(r + 3, _mm_add_sd(xy2, _mm_unpackhi_pd(xy2, xy2)));
    }
  }
}
#endif

}  // namespace

void Lockstep::forces_on_line(double angle0_rad, double step_rad, std::size_t count, double* rows,
                              bool allow_avx) const {
  const std::size_t n = filtered_[0].size();
  const auto grid = static_cast<double>(n);
  if (!(step_rad >= 0.0 && step_rad < kTwoPi)) {
    for (std::size_t i = 0; i < count; ++i) {
      const auto f = force_at(angle0_rad + step_rad * static_cast<double>(i));
      double* r = rows + 4 * i;
      r[0] = f[0];
      r[1] = f[1];
      r[2] = f[2];
      r[3] = f[0] * f[0] + f[1] * f[1];
    }
    return;
  }
  const double turns = (angle0_rad + offset_rad_) / kTwoPi;
  const GridLine line((turns - std::floor(turns)) * grid, step_rad / kTwoPi * grid, grid);
  const auto last_point = static_cast<std::int64_t>(n) - 1;
  const auto samples = static_cast<std::int64_t>(count);
#if defined(MILLWATCH_LOCKSTEP_AVX)
  if (allow_avx && signal::cpu_has_avx()) {
    line_rows_avx(line_table_.data(), line, last_point, samples, rows);
    return;
  }
#endif
  (void)allow_avx;
  line_rows_scalar(line_table_.data(), line, last_point, samples, rows);
}

}  // namespace millwatch::monitor
