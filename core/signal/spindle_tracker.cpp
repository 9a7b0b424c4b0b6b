#include "core/signal/spindle_tracker.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <complex>
#include <mutex>
#include <numbers>

#include "core/config/json_reader.hpp"
#include "core/signal/cpu_features.hpp"
#include "core/signal/fftw_planner.hpp"
#include "core/signal/harmonic_floors.hpp"
#include "core/signal/order_statistic.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace millwatch::signal {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr double kLockedSearch = 0.02;  // ± relative search range around the locked speed
// A line outside the search is reported only this far above min_snr_db (over the spectrum's
// median rather than its harmonic's own floor): a clear line, not the strongest noise bin.
constexpr double kLineMarginDb = 6.0;

double wrap_pi(double a) {
  return a - kTwoPi * std::round(a / kTwoPi);
}

/// a·b written out as std::complex computes it for finite values (without the call that checks
/// for infinities and NaN).
std::complex<double> times(std::complex<double> a, std::complex<double> b) {
  return {a.real() * b.real() - a.imag() * b.imag(), a.real() * b.imag() + a.imag() * b.real()};
}

/// DTFTs of x at two frequencies (cycles per sample), evaluated at the block's first sample.
/// In blocks of kBlock samples: within a block, sample j's phasors come from a table (a dot
/// product per block, no chain between samples); each block's sums are then turned by the
/// block's phasor, a recursion over blocks (renormalised on the unit circle now and then). A
/// phasor recursion per sample waited on its own multiply and add at every sample.
std::array<std::complex<double>, 2> dtft2(std::span<const double> x, double cycles_a,
                                          double cycles_b) {
  constexpr std::size_t kBlock = 16;
  // The table: per offset j, the phasors of a and b, interleaved (re a, re b, im a, im b) so
  // that one SSE2 pair holds a's and b's.
  alignas(16) std::array<double, 4 * kBlock> table{};
  {
    const std::complex<double> step_a = std::polar(1.0, -kTwoPi * cycles_a);
    const std::complex<double> step_b = std::polar(1.0, -kTwoPi * cycles_b);
    std::complex<double> pa(1.0, 0.0), pb(1.0, 0.0);
    for (std::size_t j = 0; j < kBlock; ++j) {
      table[4 * j] = pa.real();
      table[4 * j + 1] = pb.real();
      table[4 * j + 2] = pa.imag();
      table[4 * j + 3] = pb.imag();
      pa = times(pa, step_a);
      pb = times(pb, step_b);
    }
  }
  const auto block_dot = [&table](const double* v, std::size_t n, double out[4]) {
#if defined(__SSE2__)
    __m128d re = _mm_setzero_pd(), im = _mm_setzero_pd();    // (a, b)
    __m128d re2 = _mm_setzero_pd(), im2 = _mm_setzero_pd();  // odd j: a second chain
    std::size_t j = 0;
    for (; j + 2 <= n; j += 2) {
      const __m128d x0 = _mm_set1_pd(v[j]);
      const __m128d x1 = _mm_set1_pd(v[j + 1]);
      re = _mm_add_pd(re, _mm_mul_pd(x0, _mm_load_pd(&table[4 * j])));
      im = _mm_add_pd(im, _mm_mul_pd(x0, _mm_load_pd(&table[4 * j + 2])));
      re2 = _mm_add_pd(re2, _mm_mul_pd(x1, _mm_load_pd(&table[4 * j + 4])));
      im2 = _mm_add_pd(im2, _mm_mul_pd(x1, _mm_load_pd(&table[4 * j + 6])));
    }
    if (j < n) {
      const __m128d x0 = _mm_set1_pd(v[j]);
      re = _mm_add_pd(re, _mm_mul_pd(x0, _mm_load_pd(&table[4 * j])));
      im = _mm_add_pd(im, _mm_mul_pd(x0, _mm_load_pd(&table[4 * j + 2])));
    }
    _mm_storeu_pd(out, _mm_add_pd(re, re2));
    _mm_storeu_pd(out + 2, _mm_add_pd(im, im2));
#else
    out[0] = out[1] = out[2] = out[3] = 0.0;
    for (std::size_t j = 0; j < n; ++j) {
      for (std::size_t c = 0; c < 4; ++c) {
        out[c] += v[j] * table[4 * j + c];
      }
    }
#endif
  };
  const std::complex<double> block_step_a = std::polar(1.0, -kTwoPi * cycles_a * kBlock);
  const std::complex<double> block_step_b = std::polar(1.0, -kTwoPi * cycles_b * kBlock);
  std::complex<double> pa(1.0, 0.0), pb(1.0, 0.0);  // the block's first sample's phasors
  std::complex<double> sum_a(0.0, 0.0), sum_b(0.0, 0.0);
  std::size_t blocks = 0;
  for (std::size_t from = 0; from < x.size(); from += kBlock, ++blocks) {
    double s[4];  // Σ x·cos and Σ x·(−sin) within the block, for a and b
    block_dot(x.data() + from, std::min(kBlock, x.size() - from), s);
    sum_a += times(pa, {s[0], s[2]});
    sum_b += times(pb, {s[1], s[3]});
    pa = times(pa, block_step_a);
    pb = times(pb, block_step_b);
    if ((blocks & 63) == 63) {  // keep the phasors on the unit circle
      pa /= std::abs(pa);
      pb /= std::abs(pb);
    }
  }
  return {sum_a, sum_b};
}

/// out[k] = |in[k]| for k < n, inlined into each CPU's version of magnitudes() below.
[[gnu::always_inline]] inline void magnitude_loop(const fftw_complex* in, double* out,
                                                  std::size_t n) {
  for (std::size_t k = 0; k < n; ++k) {
    out[k] = std::sqrt(in[k][0] * in[k][0] + in[k][1] * in[k][1]);
  }
}

#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
/// magnitude_loop() four at a time (the square roots were a third of the tracker's update two
/// at a time): the same correctly rounded roots, bit for bit.
__attribute__((target("avx"))) void magnitudes_avx(const fftw_complex* in, double* out,
                                                   std::size_t n) {
  magnitude_loop(in, out, n);
}
#define MILLWATCH_TRACKER_MAGNITUDES_AVX 1
#endif

/// The spectrum's magnitudes out[k] = |in[k]|, k < n: with AVX where the CPU has it.
void magnitudes(const fftw_complex* in, double* out, std::size_t n) {
#if defined(MILLWATCH_TRACKER_MAGNITUDES_AVX)
  if (cpu_has_avx()) {
    magnitudes_avx(in, out, n);
    return;
  }
#endif
  magnitude_loop(in, out, n);
}

}  // namespace

SpindleTrackerConfig spindle_tracker_config_from_json(const nlohmann::json& j,
                                                      const std::string& path) {
  config::ObjectReader r(j, path);
  SpindleTrackerConfig c;
  c.search_fraction = r.number("search_fraction", c.search_fraction, {0.0, 0.45, true, false, ""});
  // 0 = automatic; otherwise a window of at least 20 ms.
  c.window_s = r.number("window_s", c.window_s, config::closed(0.0, 10.0, "s"));
  if (c.window_s > 0.0 && c.window_s < 0.02) {
    config::fail(r.path_of("window_s"), "value " + std::to_string(c.window_s) +
                                            " s is out of range: 0 (automatic) or [0.02, 10] s");
  }
  c.hop_s = r.number("hop_s", c.hop_s, config::closed(0.0, 10.0, "s"));
  if (c.hop_s > 0.0 && c.hop_s < 0.001) {
    config::fail(r.path_of("hop_s"), "value " + std::to_string(c.hop_s) +
                                         " s is out of range: 0 (automatic) or [0.001, 10] s");
  }
  c.max_harmonic = r.integer("max_harmonic", c.max_harmonic, 0, 64);
  c.min_snr_db = r.number("min_snr_db", c.min_snr_db, config::closed(0.0, 80.0, "dB"));
  c.phase_gain = r.number("phase_gain", c.phase_gain, {0.0, 1.0, true, false, ""});
  c.lock_agreement = r.number("lock_agreement", c.lock_agreement, config::closed(1e-5, 0.2, ""));
  c.lock_phase_rad =
      r.number("lock_phase_rad", c.lock_phase_rad, config::closed(0.01, 3.14159, "rad"));
  r.finish();
  if (c.window_s > 0.0 && c.hop_s > c.window_s) {
    config::fail(r.path_of("hop_s"), "value " + std::to_string(c.hop_s) +
                                         " s must not exceed window_s (" +
                                         std::to_string(c.window_s) + " s)");
  }
  return c;
}

nlohmann::json to_json(const SpindleTrackerConfig& c) {
  return {{"search_fraction", c.search_fraction},
          {"window_s", c.window_s},
          {"hop_s", c.hop_s},
          {"max_harmonic", c.max_harmonic},
          {"min_snr_db", c.min_snr_db},
          {"phase_gain", c.phase_gain},
          {"lock_agreement", c.lock_agreement},
          {"lock_phase_rad", c.lock_phase_rad}};
}

TrackerTiming tracker_timing(const SpindleTrackerConfig& c) {
  TrackerTiming t;
  const double rev_s = c.commanded_rpm > 0.0 ? 60.0 / c.commanded_rpm : 0.0;
  // Automatic: 10 revolutions within 0.02–0.25 s, and never fewer than validate()'s 5 (below
  // 1200 rpm the quarter second would hold fewer).
  t.window_s = c.window_s > 0.0
                   ? c.window_s
                   : std::max(std::clamp(10.0 * rev_s, 0.02, 0.25), kMinWindowRevolutions * rev_s);
  // Hann windows overlapping by half (the sum of the windows still weighs every sample the
  // same): a quarter-window hop computed twice the estimates, each sharing three quarters of its
  // samples with the last, for twice the CPU. The ramp trend (the last 6 hops) spans ~2.5
  // windows.
  t.hop_s = c.hop_s > 0.0 ? std::min(c.hop_s, t.window_s) : 0.5 * t.window_s;
  return t;
}

void validate(const SpindleTrackerConfig& c, const std::string& path) {
  const std::string at = path.empty() ? "" : path + ".";
  if (!(c.sample_rate_hz > 0.0)) {
    config::fail(at + "sample_rate_hz", "must be > 0");
  }
  if (c.flutes < 1 || c.flutes > 8) {
    config::fail(at + "flutes", "value " + std::to_string(c.flutes) + " is out of range [1, 8]");
  }
  if (!(c.commanded_rpm > 0.0)) {
    config::fail(at + "commanded_rpm", "value " + std::to_string(c.commanded_rpm) + " must be > 0");
  }
  const double f_max = c.commanded_rpm / 60.0 * (1.0 + c.search_fraction);
  if (f_max >= 0.45 * c.sample_rate_hz) {
    config::fail(at + "sample_rate_hz", "value " + std::to_string(c.sample_rate_hz) +
                                            " Hz is too low for a spindle at up to " +
                                            std::to_string(f_max) + " Hz");
  }
  if (const std::string problem = window_problem(c, at + "commanded_rpm"); !problem.empty()) {
    config::fail(at + "window_s", problem);
  }
}

std::string window_problem(const SpindleTrackerConfig& c, const std::string& rpm_name) {
  const double window_s = tracker_timing(c).window_s;
  const double revolutions = window_s * c.commanded_rpm / 60.0;
  // Within rounding of the least: the automatic window below 1200 rpm is exactly that many
  // revolutions, which window·rpm/60 can give back as 4.999… (at 1003 rpm).
  if (!(c.commanded_rpm > 0.0) || revolutions >= kMinWindowRevolutions * (1.0 - 1e-12)) {
    return {};
  }
  using config::format_number;
  const double needed_s = std::ceil(kMinWindowRevolutions * 60.0 / c.commanded_rpm * 1e4) / 1e4;
  return (c.window_s > 0.0 ? "value " + format_number(window_s) + " s"
                           : "automatic, " + format_number(window_s) + " s,") +
         " holds " + format_number(std::floor(revolutions * 100.0) / 100.0) + " revolutions at " +
         rpm_name + " " + format_number(c.commanded_rpm) + ": at least " +
         format_number(kMinWindowRevolutions) + " needed (" + format_number(needed_s) +
         " s or more)";
}

SpindleTracker::~SpindleTracker() {
  release();
}

void SpindleTracker::release() {
  if (plan_ != nullptr) {
    const std::lock_guard lock(fftw_planner_mutex());  // the planner is not thread-safe
    fftw_destroy_plan(plan_);
    plan_ = nullptr;
  }
  fftw_free(fft_in_);
  fftw_free(fft_out_);
  fft_in_ = nullptr;
  fft_out_ = nullptr;
}

void SpindleTracker::setup(const SpindleTrackerConfig& config) {
  validate(config, "spindle");
  release();
  config_ = config;
  const TrackerTiming timing = tracker_timing(config_);
  window_ = static_cast<std::size_t>(std::llround(timing.window_s * config_.sample_rate_hz));
  hop_ = std::max<std::size_t>(
      1, static_cast<std::size_t>(std::llround(timing.hop_s * config_.sample_rate_hz)));
  // Zero-padded by at least half the window: finer bins for the interpolation.
  fft_size_ = std::bit_ceil(window_ + window_ / 2);
  const double f_max = config_.commanded_rpm / 60.0 * (1.0 + config_.search_fraction);
  const int auto_harmonics = 4 * config_.flutes;
  harmonics_ = config_.max_harmonic > 0 ? config_.max_harmonic : auto_harmonics;
  harmonics_ =
      std::max(1, std::min(harmonics_, static_cast<int>(0.45 * config_.sample_rate_hz / f_max)));
  ring_.assign(window_, 0.0);
  hann_.resize(window_);
  for (std::size_t n = 0; n < window_; ++n) {
    hann_[n] = 0.5 - 0.5 * std::cos(kTwoPi * static_cast<double>(n) / static_cast<double>(window_));
  }
  magnitude_.assign(fft_size_ / 2 + 1, 0.0);
  // The highest bin update() reads: the harmonics' peaks up to the highest speed searched and
  // their floors two spindle frequencies beyond, with a few bins of interpolation and lobe.
  const double bin = bin_hz();
  magnitude_bins_ = std::min(
      magnitude_.size(), static_cast<std::size_t>(std::ceil((harmonics_ + 2) * f_max / bin)) + 8);
  floors_.resize(fft_size_ / 2 + 1);
  line_scratch_.assign(2 * magnitude_bins_, 0.0);
  past_.assign(2 * (window_ / hop_) + 3, Past{});  // two windows back: a ramp's three windows
  fft_in_ = fftw_alloc_real(fft_size_);
  fft_out_ = fftw_alloc_complex(fft_size_ / 2 + 1);
  {
    const std::lock_guard lock(fftw_planner_mutex());  // the planner is not thread-safe
    plan_ = fftw_plan_dft_r2c_1d(static_cast<int>(fft_size_), fft_in_, fft_out_, FFTW_ESTIMATE);
  }
  restart(0);
}

void SpindleTracker::restart(std::int64_t next_sample) {
  next_sample_ = next_sample;
  slot_ =
      window_ > 0 ? static_cast<std::size_t>(next_sample % static_cast<std::int64_t>(window_)) : 0;
  stream_start_ = next_sample;
  since_hop_ = 0;
  locked_ = false;
  past_count_ = 0;
  recent_count_ = 0;
  estimate_ = {};
  phase_ = {};
}

void SpindleTracker::remember(bool cutting, double hz, double tooth_phase_rad,
                              std::int64_t center) {
  past_[static_cast<std::size_t>(past_count_ % static_cast<int>(past_.size()))] = {
      cutting, hz, tooth_phase_rad, center};
  ++past_count_;
}

const SpindleTracker::Past* SpindleTracker::window_ago(std::int64_t center) const {
  // The newest remembered window that ends before this one begins (give or take the rounding
  // of hops to samples).
  const auto cap = static_cast<int>(past_.size());
  for (int i = past_count_ - 1; i >= std::max(0, past_count_ - cap); --i) {
    const Past& p = past_[static_cast<std::size_t>(i % cap)];
    if (center - p.center >= static_cast<std::int64_t>(window_ - window_ / 100)) {
      return &p;
    }
  }
  return nullptr;
}

bool SpindleTracker::on_a_ramp(const Past& earlier, double hz, std::int64_t center) const {
  // A ramp changes the speed by more than lock_agreement in a window (at 10,000 rpm, 10
  // revolutions' window: beyond 1,700 rpm/s): three windows a window apart on one straight line
  // of speed, both pairs' tooth phases as the mean speeds predict (exact on a linear ramp).
  // Three random speeds rarely fall on a line, and two phase checks pass by chance more rarely.
  const Past* before = window_ago(earlier.center);
  if (before == nullptr || !before->cutting) {
    return false;
  }
  const double fs = config_.sample_rate_hz;
  const double dt1_s = static_cast<double>(earlier.center - before->center) / fs;
  const double dt_s = static_cast<double>(center - earlier.center) / fs;
  const double predicted_hz = earlier.hz + (earlier.hz - before->hz) / dt1_s * dt_s;
  const double phase_predicted =
      before->tooth_phase_rad + kTwoPi * config_.flutes * 0.5 * (earlier.hz + before->hz) * dt1_s;
  return std::fabs(hz - predicted_hz) <= config_.lock_agreement * hz &&
         std::fabs(wrap_pi(earlier.tooth_phase_rad - phase_predicted)) <= config_.lock_phase_rad;
}

int SpindleTracker::process(std::span<const double> samples) {
  int updates = 0;
  for (double x : samples) {
    ring_[slot_] = x;
    slot_ = slot_ + 1 == window_ ? 0 : slot_ + 1;
    ++next_sample_;
    ++since_hop_;
    if (since_hop_ >= hop_ && next_sample_ - stream_start_ >= static_cast<std::int64_t>(window_)) {
      since_hop_ = 0;
      update();
      ++updates;
    }
  }
  return updates;
}

double SpindleTracker::magnitude_at(double f_hz) const {
  const double pos = f_hz * static_cast<double>(fft_size_) / config_.sample_rate_hz;
  const auto k = static_cast<std::size_t>(pos);
  if (k + 1 >= magnitude_.size()) {
    return 0.0;
  }
  const double w = pos - static_cast<double>(k);
  return (1.0 - w) * magnitude_[k] + w * magnitude_[k + 1];
}

double SpindleTracker::peak_offset_bins(std::size_t k) const {
  // A parabola through the log-magnitudes of bins k − 1, k, k + 1 (a Hann-windowed line's is
  // nearly one).
  const double l0 = std::log(magnitude_[k - 1]);
  const double l1 = std::log(magnitude_[k]);
  const double l2 = std::log(magnitude_[k + 1]);
  const double denom = l0 - 2.0 * l1 + l2;
  return denom < 0.0 ? 0.5 * (l0 - l2) / denom : 0.0;
}

bool SpindleTracker::line_fits(double line_hz, double f_hz) const {
  // A spindle's strongest line is one of its harmonics: its own frequency (runout), the
  // tooth-passing one or a multiple, or another where runout shapes the pulses (a 2-flute slot,
  // f_t 2 µm, ρ 0.8 µm: the third).
  const double h = std::max(1.0, std::round(line_hz / f_hz));
  return std::fabs(line_hz - h * f_hz) <= 1.5 * bin_hz();
}

void SpindleTracker::find_strongest_line(SpindleEstimate& e) {
  const double bin = bin_hz();
  const double f_cmd = config_.commanded_rpm / 60.0;
  const double f_lo = f_cmd * (1.0 - config_.search_fraction);
  const double f_hi = f_cmd * (1.0 + config_.search_fraction);
  const int z = config_.flutes;
  // From half the slowest spindle frequency searched (below it: drift) to the second
  // tooth-passing harmonic of the fastest: higher up, the spectrum of a force magnitude with
  // kinks holds small lines of every order and aliases from the decimation (a 2-flute slot
  // without runout at 50 kHz: its sixth tooth-passing harmonic, 4,947 Hz, folded to 3,386 Hz,
  // the strongest there).
  const auto first =
      std::max<std::size_t>(3, static_cast<std::size_t>(std::ceil(0.5 * f_lo / bin)));
  const std::size_t last =
      std::min({magnitude_bins_ - 2, static_cast<std::size_t>(0.45 * config_.sample_rate_hz / bin),
                static_cast<std::size_t>(std::ceil(2 * z * f_hi / bin)) + 2});
  if (last <= first + 16) {
    return;
  }
  std::size_t k = first;
  for (std::size_t c = first; c <= last; ++c) {
    if (magnitude_[c] > magnitude_[k]) {
      k = c;
    }
  }
  const std::size_t n = last - first + 1;
  const std::span<double> values(line_scratch_.data(), n);
  std::copy_n(magnitude_.begin() + static_cast<std::ptrdiff_t>(first), n, values.begin());
  const double median = kth_smallest(values, n / 2, std::span<double>(line_scratch_.data() + n, n));
  const double m = magnitude_[k];
  if (!(m > 0.0) || !(median > 0.0)) {
    return;
  }
  // At the band's edges the strongest bin need not be a peak: the offset stays within its bin.
  e.line_hz = (static_cast<double>(k) + std::clamp(peak_offset_bins(k), -0.5, 0.5)) * bin;
  e.line_snr_db = 20.0 * std::log10(m / median);
  const double clear = median * std::pow(10.0, config_.min_snr_db / 20.0);
  // A line within a bin of hz: a peak there (not the flank of one a few bins away), clear.
  const auto line_near = [&](double hz) {
    const auto c = static_cast<std::size_t>(std::lround(hz / bin));
    if (c < 2 || c + 2 >= magnitude_bins_) {
      return false;
    }
    std::size_t p = c - 1;
    for (std::size_t q = c; q <= c + 1; ++q) {
      p = magnitude_[q] > magnitude_[p] ? q : p;
    }
    return magnitude_[p] >= clear && magnitude_[p] >= magnitude_[p - 1] &&
           magnitude_[p] >= magnitude_[p + 1];
  };
  // A spindle's line: clear of the noise, with a line of its family beside it — the spindle
  // line below a tooth-passing one (runout), or its own second or z-th harmonic. An isolated
  // line (hum, a pump, a resonance, chatter) is none.
  e.line_has_spindle_line = z > 1 && line_near(e.line_hz / z);
  e.line_of_a_spindle =
      e.line_snr_db >= config_.min_snr_db + kLineMarginDb &&
      (e.line_has_spindle_line || line_near(2.0 * e.line_hz) || line_near(z * e.line_hz));
  // Explained by a speed searched: some f = line/h within the range (a bin wider at both ends)
  // with a line of its own at f or at the tooth-passing z·f, as a lock needs.
  bool explained = false;
  for (int h = 1; !explained && e.line_hz / h >= f_lo - 1.5 * bin / h; ++h) {
    const double f = e.line_hz / h;
    explained = f <= f_hi + 1.5 * bin / h && (line_near(f) || line_near(z * f));
  }
  e.line_outside_search = e.line_of_a_spindle && !explained;
}

double SpindleTracker::harmonic_score(double f_hz) const {
  double sum = 0.0;
  for (int h = 1; h <= harmonics_; ++h) {
    sum += magnitude_at(h * f_hz);
  }
  return sum / harmonics_;
}

void SpindleTracker::update() {
  // The window, oldest sample first, without its mean, Hann-weighted, zero-padded.
  const auto w = static_cast<std::int64_t>(window_);
  const std::int64_t first = next_sample_ - w;
  // The ring from the oldest sample's slot to its end, then from its start: two runs.
  const auto split = static_cast<std::size_t>(first % w);
  const std::size_t tail = window_ - split;
  // The mean in the ring's own order (a sum does not care which sample is oldest), in four
  // chains that do not wait on one another: one chain had been a tenth of this function.
  std::array<double, 4> part{};
  std::size_t slot = 0;
  for (; slot + 4 <= window_; slot += 4) {
    part[0] += ring_[slot];
    part[1] += ring_[slot + 1];
    part[2] += ring_[slot + 2];
    part[3] += ring_[slot + 3];
  }
  for (; slot < window_; ++slot) {
    part[0] += ring_[slot];
  }
  const double mean = ((part[0] + part[1]) + (part[2] + part[3])) / static_cast<double>(window_);
  for (std::size_t i = 0; i < tail; ++i) {
    fft_in_[i] = (ring_[split + i] - mean) * hann_[i];
  }
  for (std::size_t i = tail; i < window_; ++i) {
    fft_in_[i] = (ring_[i - tail] - mean) * hann_[i];
  }
  std::fill(fft_in_ + window_, fft_in_ + fft_size_, 0.0);
  fftw_execute(plan_);
  // Only the bins the search and the floors can reach (the rest stay 0, never read).
  magnitudes(fft_out_, magnitude_.data(), magnitude_bins_);

  estimate_.line_hz = 0.0;
  estimate_.line_snr_db = 0.0;
  estimate_.line_outside_search = false;
  estimate_.line_has_spindle_line = false;
  estimate_.line_of_a_spindle = false;
  estimate_.alias_refused = false;
  if (!locked_) {
    find_strongest_line(estimate_);
  }

  // Coarse search over the commanded range, a quarter of a (padded) bin at a time.
  const double bin = bin_hz();
  const double f_cmd = config_.commanded_rpm / 60.0;
  double f_lo = f_cmd * (1.0 - config_.search_fraction);
  double f_hi = f_cmd * (1.0 + config_.search_fraction);
  if (locked_) {  // while locked, a narrow range around the last speed is enough (and cheaper)
    f_lo = std::max(f_lo, phase_.spindle_hz * (1.0 - kLockedSearch));
    f_hi = std::min(f_hi, phase_.spindle_hz * (1.0 + kLockedSearch));
  }
  double best_f = f_lo;
  double best_score = -1.0;
  for (double f = f_lo; f <= f_hi; f += 0.25 * bin) {
    const double s = harmonic_score(f);
    if (s > best_score) {
      best_score = s;
      best_f = f;
    }
  }

  // Refine with every harmonic standing clear of its own neighbourhood: a spectral line, not
  // a hump of coloured noise. A harmonic's floor is the median magnitude within two spindle
  // frequencies of it, outside every harmonic's main lobe (Hann: ±2 bins of the unpadded
  // window) — enough independent bins for a steady median even with a short window.
  const double lobe = 2.0 * static_cast<double>(fft_size_) / static_cast<double>(window_) + 1.0;
  const double harmonic_bins = best_f / bin;
  const auto reach = static_cast<std::size_t>(2.0 * harmonic_bins);
  // Which bins lie outside every harmonic's lobe, once for all harmonics (their neighbourhoods
  // overlap).
  const std::size_t last_bin =
      std::min(magnitude_.size() - 1,
               static_cast<std::size_t>(std::lround(harmonics_ * harmonic_bins)) + reach + 1);
  floors_.prepare(magnitude_, harmonic_bins, lobe, last_bin);
  double sum_w = 0.0, sum_wf = 0.0, sum_wff = 0.0, sum_peak = 0.0, sum_floor = 0.0;
  int used = 0;
  bool own_line = false;  // a line stands at f or at the tooth-passing z·f
  for (int h = 1; h <= harmonics_; ++h) {
    const auto center = static_cast<std::size_t>(std::lround(h * best_f / bin));
    if (center < 3 || center + 3 >= magnitude_.size()) {
      continue;
    }
    std::size_t k = center;
    for (std::size_t c = center - 2; c <= center + 2; ++c) {
      if (magnitude_[c] > magnitude_[k]) {
        k = c;
      }
    }
    const std::size_t from = center > reach + 1 ? center - reach : 1;
    const std::size_t to = std::min({magnitude_.size() - 1, center + reach, last_bin});
    if (floors_.count(from, to) < 8) {
      continue;
    }
    const double floor = std::max(floors_.median(from, to), 1e-300);
    const double m = magnitude_[k];
    sum_peak += m;
    sum_floor += floor;
    if (m < 4.0 * floor) {
      continue;
    }
    own_line = own_line || h == 1 || h == config_.flutes;
    const double f_h = (static_cast<double>(k) + peak_offset_bins(k)) * bin / h;
    const double weight = (h * m) * (h * m);
    sum_w += weight;
    sum_wf += weight * f_h;
    sum_wff += weight * f_h * f_h;
    ++used;
  }

  SpindleEstimate& e = estimate_;
  ++e.updates;
  e.relocked = false;
  e.consistent = false;
  e.agreement = 0.0;
  e.phase_error_rad = 0.0;
  e.center_sample = first + w / 2;
  // The harmonics together over their floors: noise peaks at a few harmonics do not add up.
  e.snr_db = 20.0 * std::log10(std::max(sum_peak, 1e-300) / std::max(sum_floor, 1e-300));
  e.cutting = e.snr_db >= config_.min_snr_db && used > 0;
  if (!e.cutting) {
    e.valid = false;
    locked_ = false;
    remember(false, 0.0, 0.0, e.center_sample);
    recent_count_ = 0;
    phase_.valid = false;
    return;
  }
  const double f = sum_wf / sum_w;
  const double spread = std::sqrt(std::max(0.0, sum_wff / sum_w - f * f));
  e.spindle_hz = f;
  e.spindle_rpm = 60.0 * f;
  e.uncertainty_rpm = 60.0 * spread / std::sqrt(static_cast<double>(used));

  // Phase at the window centre from the fundamental and the tooth harmonic (exact DTFTs of the
  // windowed block; the Hann window is symmetric, so it adds no phase at the centre).
  const std::span<const double> block(fft_in_, window_);
  const double centre = static_cast<double>(w / 2);
  const int z = config_.flutes;
  const auto [c1, cz] = dtft2(block, f / config_.sample_rate_hz, z * f / config_.sample_rate_hz);
  const double phi1 = std::arg(c1) + kTwoPi * f * centre / config_.sample_rate_hz;
  const double phiz = std::arg(cz) + kTwoPi * z * f * centre / config_.sample_rate_hz;
  double angle = phi1;
  if (z > 1) {
    double best = 1e9;
    for (int m = 0; m < z; ++m) {
      const double candidate = (phiz + kTwoPi * m) / z;
      const double miss = std::fabs(wrap_pi(candidate - phi1));
      if (miss < best) {
        best = miss;
        angle = candidate;
      }
    }
  }
  e.angle_rad = std::fmod(std::fmod(angle, kTwoPi) + kTwoPi, kTwoPi);

  // Agreement with the window one window length earlier (no samples shared): the speeds, and
  // the tooth phase that window predicts here at the mean of the two speeds.
  const double n_c = static_cast<double>(e.center_sample);
  if (const Past* earlier = window_ago(e.center_sample); earlier != nullptr && earlier->cutting) {
    const double dt =
        static_cast<double>(e.center_sample - earlier->center) / config_.sample_rate_hz;
    const double predicted = earlier->tooth_phase_rad + kTwoPi * z * 0.5 * (f + earlier->hz) * dt;
    e.agreement = std::fabs(f - earlier->hz) / f;
    e.phase_error_rad = wrap_pi(phiz - predicted);
    const bool phase_agrees = std::fabs(e.phase_error_rad) <= config_.lock_phase_rad;
    e.consistent = phase_agrees && (e.agreement <= config_.lock_agreement ||
                                    on_a_ramp(*earlier, f, e.center_sample));
  }
  remember(true, f, phiz, e.center_sample);

  // Speed trend over the recent hops (least squares), for ramps.
  const double t_c = n_c / config_.sample_rate_hz;
  const int cap = static_cast<int>(recent_hz_.size());
  if (recent_count_ == cap) {
    std::rotate(recent_hz_.begin(), recent_hz_.begin() + 1, recent_hz_.end());
    std::rotate(recent_center_s_.begin(), recent_center_s_.begin() + 1, recent_center_s_.end());
    --recent_count_;
  }
  recent_hz_[static_cast<std::size_t>(recent_count_)] = f;
  recent_center_s_[static_cast<std::size_t>(recent_count_)] = t_c;
  ++recent_count_;
  double slope = 0.0;
  if (recent_count_ >= 3) {
    double mt = 0.0, mf = 0.0;
    for (int i = 0; i < recent_count_; ++i) {
      mt += recent_center_s_[static_cast<std::size_t>(i)];
      mf += recent_hz_[static_cast<std::size_t>(i)];
    }
    mt /= recent_count_;
    mf /= recent_count_;
    double stt = 0.0, stf = 0.0;
    for (int i = 0; i < recent_count_; ++i) {
      const double dt = recent_center_s_[static_cast<std::size_t>(i)] - mt;
      stt += dt * dt;
      stf += dt * (recent_hz_[static_cast<std::size_t>(i)] - mf);
    }
    slope = stt > 0.0 ? stf / stt : 0.0;
  }

  if (locked_) {
    // The tooth phase against the locked model, modulo one pitch: the flute picked at the lock
    // stays picked even when a weak fundamental would pick another.
    const double pitch = kTwoPi / z;
    const double error = pitch * wrap_pi((angle - phase_.angle_at(n_c)) * z) / kTwoPi;
    if (std::fabs(error * z) < 1.0) {
      // Re-anchor at the newest sample, continuous there: the window's news is half a window
      // old, so a new speed extrapolated from its centre would make the angle now jump. Part
      // of the phase error is corrected; the speed now is the window's plus its trend.
      const double n_now = static_cast<double>(next_sample_ - 1);
      const double angle_now = phase_.angle_at(n_now) + config_.phase_gain * error;
      phase_.reference_sample = n_now;
      phase_.reference_angle_rad = angle_now;
      phase_.spindle_hz = f + slope * (n_now - n_c) / config_.sample_rate_hz;
      phase_.spindle_hz_per_s = slope;
      e.valid = true;
      return;
    }
    // The phase jumped: the cut changed (stop/start, a new tool...). Lock afresh when
    // consistent again.
    locked_ = false;
    phase_.valid = false;
    find_strongest_line(e);  // as every window that starts unlocked
  }
  if (!e.consistent) {
    e.valid = false;
    return;
  }
  if (!own_line || (e.line_of_a_spindle && !line_fits(e.line_hz, f))) {
    // No line at this speed's own frequency nor at its tooth-passing one, or the window's
    // strongest line is none this speed makes: an alias (harmonics of a speed outside the
    // search that fall on some of this speed's: 40,000 rpm seen from 25,000 commanded as
    // 26,667, whose third and sixth harmonics are its tooth-passing lines), not a lock.
    e.alias_refused = true;
    e.valid = false;
    e.consistent = false;
    return;
  }
  locked_ = true;
  e.valid = true;
  e.relocked = true;
  phase_.valid = true;
  phase_.reference_sample = n_c;
  phase_.reference_angle_rad = e.angle_rad;
  phase_.spindle_hz = f;
  phase_.spindle_hz_per_s = recent_count_ >= 3 ? slope : 0.0;
  phase_.sample_rate_hz = config_.sample_rate_hz;
}

}  // namespace millwatch::signal
