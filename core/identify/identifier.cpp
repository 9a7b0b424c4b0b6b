#include "core/identify/identifier.hpp"

#include <chrono>
#include <utility>

namespace millwatch::identify {

Identifier::Identifier(const model::ModelConfig& model, FilterResponse filter, FitOptions options,
                       Callback on_result)
    : fitter_(model, std::move(filter), std::move(options)),
      on_result_(std::move(on_result)),
      worker_([this] { run(); }) {}

Identifier::~Identifier() {
  finish();
}

void Identifier::submit(const MeasuredRevolution& window, std::int64_t revolution,
                        std::int64_t utime_us) {
  {
    const std::lock_guard lock(mutex_);
    if (stop_) {
      return;
    }
    superseded_ += pending_.has_value() ? 1 : 0;
    pending_ = window;
    pending_revolution_ = revolution;
    pending_utime_us_ = utime_us;
  }
  wake_.notify_one();
}

void Identifier::finish() {
  {
    const std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_one();
  if (worker_.joinable()) {
    worker_.join();
  }
}

std::optional<IdentifiedWindow> Identifier::latest() const {
  const std::lock_guard lock(mutex_);
  return latest_;
}

std::int64_t Identifier::fitted() const {
  const std::lock_guard lock(mutex_);
  return fitted_;
}

std::int64_t Identifier::superseded() const {
  const std::lock_guard lock(mutex_);
  return superseded_;
}

void Identifier::run() {
  std::optional<FitResult> previous;
  for (;;) {
    MeasuredRevolution window;
    IdentifiedWindow out;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [this] { return stop_ || pending_.has_value(); });
      if (!pending_.has_value()) {
        return;  // stopped with nothing waiting
      }
      window = std::move(*pending_);
      pending_.reset();
      out.revolution = pending_revolution_;
      out.utime_us = pending_utime_us_;
    }
    out.window_revolutions = window.revolutions;
    const auto start = std::chrono::steady_clock::now();
    out.fit = fitter_.fit(window, previous ? &*previous : nullptr);
    out.fit_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (out.fit.ok) {
      previous = out.fit;
    }
    {
      const std::lock_guard lock(mutex_);
      latest_ = out;
      ++fitted_;
    }
    if (on_result_) {
      on_result_(out);
    }
  }
}

}  // namespace millwatch::identify
