#include "core/monitor/model_builder.hpp"

#include <utility>

#include "core/monitor/background_thread.hpp"

namespace millwatch::monitor {

ModelBuilder::ModelBuilder(const model::ModelConfig& model, const signal::ButterworthDesign& filter,
                           bool zero_phase)
    : model_(model), commanded_(model), filter_(filter), zero_phase_(zero_phase), thread_([this] {
        run();
      }) {}

ModelBuilder::~ModelBuilder() {
  {
    const std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_one();
  thread_.join();
}

void ModelBuilder::start(const model::ModelConfig& commanded, double spindle_hz) {
  {
    const std::lock_guard lock(mutex_);
    commanded_ = commanded;
    spindle_hz_ = spindle_hz;
    requested_ = true;
    finished_ = false;
  }
  busy_ = true;
  wake_.notify_one();
}

void ModelBuilder::take_into(Lockstep& lockstep) {
  std::unique_lock lock(mutex_);
  done_.wait(lock, [this] { return finished_; });
  busy_ = false;
  finished_ = false;
  if (error_) {
    std::rethrow_exception(std::exchange(error_, nullptr));
  }
  lockstep.take_model(*spare_);
}

void ModelBuilder::run() {
  make_this_thread_batch();  // a build's wake-up does not preempt the sample thread
  try {
    spare_.emplace(model_, filter_, zero_phase_);  // model_, filter_: never written after
  } catch (...) {
    spare_error_ = std::current_exception();
  }
  std::unique_lock lock(mutex_);
  for (;;) {
    wake_.wait(lock, [this] { return requested_ || stop_; });
    if (stop_) {
      return;
    }
    requested_ = false;
    // The request and the spare are this thread's until finished_ is set: start() is not
    // called while busy, and take_into() reads the spare only after finished_.
    lock.unlock();
    std::exception_ptr error = spare_error_;
    if (spare_) {
      try {
        spare_->build(commanded_, spindle_hz_);
      } catch (...) {
        error = std::current_exception();
      }
    }
    lock.lock();
    error_ = error;
    finished_ = true;
    done_.notify_one();
  }
}

}  // namespace millwatch::monitor
