#include "core/signal/zero_phase_filter.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace millwatch::signal {

ZeroPhaseFilter::ZeroPhaseFilter(const ButterworthDesign& design, int channels,
                                 std::size_t chunk_samples)
    : design_(design), margin_(margin_samples(design)) {
  if (channels < 1) {
    throw std::invalid_argument("ZeroPhaseFilter: channels must be at least 1");
  }
  chunk_ = chunk_samples > 0 ? chunk_samples : std::max<std::size_t>(4 * margin_, 4096);
  pad_ = filtfilt_pad_samples(design, std::numeric_limits<std::size_t>::max() / 2);
  const auto n = static_cast<std::size_t>(channels);
  forward_.assign(n, LowPassFilter(design));
  forward_out_.assign(n, std::vector<double>(chunk_ + margin_ + pad_, 0.0));
  out_.assign(n, std::vector<double>(chunk_ + margin_ + pad_, 0.0));
  recent_in_.assign(n, std::vector<double>(pad_ + 1, 0.0));
}

std::size_t ZeroPhaseFilter::margin_samples(const ButterworthDesign& design) {
  return decay_samples(design, 1e-12) + 1;
}

std::size_t ZeroPhaseFilter::push(std::span<const double> x) {
  if (x.size() != forward_.size() || forward_.empty()) {
    throw std::invalid_argument("ZeroPhaseFilter::push: expected one sample per channel");
  }
  const std::size_t ring = pad_ + 1;
  for (std::size_t c = 0; c < x.size(); ++c) {
    recent_in_[c][stretch_samples_ % ring] = x[c];
  }
  ++stretch_samples_;
  if (stretch_samples_ < ring) {
    return 0;  // collecting the start of the stretch for its reflection
  }
  if (stretch_samples_ == ring) {
    start_forward(ring);
  } else {
    for (std::size_t c = 0; c < x.size(); ++c) {
      forward_out_[c][held_] = forward_[c].step(x[c]);
    }
    ++held_;
  }
  return held_ >= chunk_ + margin_ ? emit(chunk_) : 0;
}

void ZeroPhaseFilter::start_forward(std::size_t count) {
  // As filtfilt does at the start of a record: the forward pass starts from the steady state of
  // an odd reflection of the first inputs, 2·x[0] − x[k], and runs through it into the signal.
  for (std::size_t c = 0; c < forward_.size(); ++c) {
    const std::vector<double>& in = recent_in_[c];
    const std::size_t p = count - 1;
    forward_[c].reset();
    forward_[c].settle(2.0 * in[0] - in[p]);
    for (std::size_t k = p; k >= 1; --k) {
      forward_[c].step(2.0 * in[0] - in[k]);
    }
    for (std::size_t i = 0; i < count; ++i) {
      forward_out_[c][held_ + i] = forward_[c].step(in[i]);
    }
  }
  held_ += count;
}

std::size_t ZeroPhaseFilter::flush() {
  if (stretch_samples_ == 0) {
    return 0;
  }
  if (stretch_samples_ <= pad_) {
    start_forward(stretch_samples_);  // a stretch shorter than the reflection
  }
  // As filtfilt does at the end of a record: run the forward pass on through an odd reflection
  // of the last inputs, 2·x[n−1] − x[n−1−k], so that the backward pass starts past the end of
  // the signal rather than on the forward pass's lagging last value.
  const std::size_t reflect = std::min<std::size_t>(pad_, stretch_samples_ - 1);
  const std::size_t ring = pad_ + 1;
  const std::size_t last = (stretch_samples_ - 1) % ring;
  for (std::size_t c = 0; c < forward_.size(); ++c) {
    const std::vector<double>& in = recent_in_[c];
    for (std::size_t k = 1; k <= reflect; ++k) {
      const double x = 2.0 * in[last] - in[(last + ring - k) % ring];
      forward_out_[c][held_ + k - 1] = forward_[c].step(x);
    }
  }
  const std::size_t count = held_;
  held_ += reflect;
  emit(count);
  held_ = 0;
  stretch_samples_ = 0;
  return count;
}

std::size_t ZeroPhaseFilter::emit(std::size_t count) {
  for (std::size_t c = 0; c < forward_.size(); ++c) {
    const std::vector<double>& y = forward_out_[c];
    LowPassFilter backward(design_);
    backward.settle(y[held_ - 1]);
    for (std::size_t i = held_; i-- > 0;) {
      out_[c][i] = backward.step(y[i]);
    }
    // The samples beyond `count` stay held; their backward output is recomputed next time.
    std::copy(forward_out_[c].begin() + static_cast<std::ptrdiff_t>(count),
              forward_out_[c].begin() + static_cast<std::ptrdiff_t>(held_),
              forward_out_[c].begin());
  }
  held_ -= count;
  return count;
}

}  // namespace millwatch::signal
