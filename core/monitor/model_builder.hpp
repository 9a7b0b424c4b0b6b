#pragma once
// The lockstep model's rebuilds at a new speed, off the sample thread.
//
// Following the speed re-evaluates the model's steady state and its filter: 0.16 ms for the
// plain model, but 4.3 ms for [000]'s full model on the Zen 5 (bench/model_benchmark's
// BM_LockstepRebuild*) — done in the sample thread, a stall that the revolution it falls in
// waits out, far beyond the 1 ms latency target, and through a ramp one every 0.2 % of speed.
// The builder evaluates it on a thread of its own into a spare Lockstep; the pipeline takes it
// a fixed number of revolutions after asking (Pipeline: 20 ms of revolutions at the commanded
// speed), waiting only if it is not done by then. Which revolution the new model applies from
// is thus fixed by the samples alone: the same in a live run and in its replay, whatever the
// machine or the pacing.
//
// One build at a time; start() and take_into() from one thread (the sample thread). Allocates
// at construction (the thread; the spare on it); start() and take_into() allocate nothing beyond
// what the build itself does on the builder's thread.

#include <condition_variable>
#include <exception>
#include <mutex>
#include <optional>
#include <thread>

#include "core/model/model_config.hpp"
#include "core/monitor/lockstep.hpp"

namespace millwatch::monitor {

class ModelBuilder {
 public:
  /// The spare: Lockstep(model, filter, zero_phase), as the pipeline's own, made on the
  /// builder's thread (its workspace for [000]'s full model takes milliseconds to set up).
  ModelBuilder(const model::ModelConfig& model, const signal::ButterworthDesign& filter,
               bool zero_phase);
  ~ModelBuilder();  ///< waits for a build in progress, then stops the thread
  ModelBuilder(const ModelBuilder&) = delete;
  ModelBuilder& operator=(const ModelBuilder&) = delete;

  /// Starts building `commanded`'s model at `spindle_hz` on the builder's thread. Not while
  /// busy().
  void start(const model::ModelConfig& commanded, double spindle_hz);
  /// A build started and not yet taken.
  [[nodiscard]] bool busy() const { return busy_; }
  /// The speed of the build started last (Hz).
  [[nodiscard]] double spindle_hz() const { return spindle_hz_; }
  /// Waits for the build started last, then swaps its model into `lockstep`
  /// (Lockstep::take_model: the alignment stays). Rethrows what the build (or making the spare)
  /// threw. While busy().
  void take_into(Lockstep& lockstep);

 private:
  void run();

  std::optional<Lockstep> spare_;   // made by run() from model_
  std::exception_ptr spare_error_;  // what making it threw (every build then fails with it)
  const model::ModelConfig model_;
  model::ModelConfig commanded_;  // the build asked for
  signal::ButterworthDesign filter_;
  bool zero_phase_ = false;
  double spindle_hz_ = 0.0;
  bool busy_ = false;  // the calling thread's: started, not taken

  std::mutex mutex_;
  std::condition_variable wake_;  // the builder's: a build asked for, or stop
  std::condition_variable done_;  // take_into()'s: the build ended
  bool requested_ = false;
  bool finished_ = false;
  bool stop_ = false;
  std::exception_ptr error_;
  std::thread thread_;  // last: started once the rest is set up
};

}  // namespace millwatch::monitor
