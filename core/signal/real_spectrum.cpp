#include "core/signal/real_spectrum.hpp"

#include <fftw3.h>

#include <algorithm>
#include <mutex>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/signal/fftw_planner.hpp"

namespace millwatch::signal {

RealSpectrum::RealSpectrum(int samples) {
  if (samples < 1) {
    throw std::invalid_argument("RealSpectrum: samples must be >= 1, got " +
                                std::to_string(samples));
  }
  samples_ = samples;
  const auto n = static_cast<std::size_t>(samples);
  const std::lock_guard lock(fftw_planner_mutex());  // fftw_planner.hpp
  time_ = fftw_alloc_real(n);
  auto* spectrum = fftw_alloc_complex(n / 2 + 1);
  spectrum_ = reinterpret_cast<std::complex<double>*>(spectrum);
  if (time_ != nullptr && spectrum != nullptr) {
    plan_ = fftw_plan_dft_r2c_1d(samples, time_, spectrum, FFTW_ESTIMATE);
  }
  if (plan_ == nullptr) {
    fftw_free(time_);
    fftw_free(spectrum_);
    time_ = nullptr;
    spectrum_ = nullptr;
    samples_ = 0;
    throw std::runtime_error("RealSpectrum: FFTW could not set up " + std::to_string(n) +
                             " points");
  }
}

RealSpectrum::~RealSpectrum() {
  release();
}

RealSpectrum::RealSpectrum(RealSpectrum&& other) noexcept
    : samples_(std::exchange(other.samples_, 0)),
      time_(std::exchange(other.time_, nullptr)),
      spectrum_(std::exchange(other.spectrum_, nullptr)),
      plan_(std::exchange(other.plan_, nullptr)) {}

RealSpectrum& RealSpectrum::operator=(RealSpectrum&& other) noexcept {
  if (this != &other) {
    release();
    samples_ = std::exchange(other.samples_, 0);
    time_ = std::exchange(other.time_, nullptr);
    spectrum_ = std::exchange(other.spectrum_, nullptr);
    plan_ = std::exchange(other.plan_, nullptr);
  }
  return *this;
}

void RealSpectrum::release() {
  if (plan_ == nullptr) {
    return;
  }
  const std::lock_guard lock(fftw_planner_mutex());  // fftw_planner.hpp
  fftw_destroy_plan(plan_);
  fftw_free(time_);
  fftw_free(spectrum_);
  plan_ = nullptr;
  time_ = nullptr;
  spectrum_ = nullptr;
  samples_ = 0;
}

std::span<const std::complex<double>> RealSpectrum::transform(std::span<const double> x) {
  if (plan_ == nullptr || x.size() != static_cast<std::size_t>(samples_)) {
    throw std::invalid_argument("RealSpectrum::transform: " + std::to_string(x.size()) +
                                " samples, the plan is for " + std::to_string(samples_));
  }
  std::copy(x.begin(), x.end(), time_);
  fftw_execute(plan_);
  return {spectrum_, static_cast<std::size_t>(samples_ / 2 + 1)};
}

std::complex<double> RealSpectrum::bin(int k) const {
  if (samples_ == 0 || k < 0) {
    throw std::invalid_argument("RealSpectrum::bin: bin " + std::to_string(k) + " of " +
                                std::to_string(samples_) + " samples");
  }
  const int r = k % samples_;
  return r <= samples_ / 2 ? spectrum_[r] : std::conj(spectrum_[samples_ - r]);
}

}  // namespace millwatch::signal
