#pragma once
// Continuous identification: the monitor's synchronous-average windows are fitted in a worker
// thread, never in the caller's (the sample thread only copies a window and signals). A window
// that arrives while a fit runs replaces the one waiting: the worker always fits the newest,
// seeded with its previous result.
//
//   Identifier id(model, filter, options, [](const IdentifiedWindow& w) { publish(w); });
//   id.submit(window);           // from the sample thread: a copy under a mutex, no fit
//   ...
//   id.finish();                 // waits for the window in progress and the one waiting

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>

#include "core/identify/window_fit.hpp"

namespace millwatch::identify {

/// One fitted window.
struct IdentifiedWindow {
  FitResult fit;
  std::int64_t revolution = 0;  ///< last revolution of the window
  std::int64_t utime_us = 0;    ///< its end
  int window_revolutions = 0;
  double fit_seconds = 0.0;  ///< wall-clock time the fit took
};

class Identifier {
 public:
  using Callback = std::function<void(const IdentifiedWindow&)>;

  /// @param on_result called in the worker thread after each fit
  Identifier(const model::ModelConfig& model, FilterResponse filter, FitOptions options,
             Callback on_result);
  ~Identifier();
  Identifier(const Identifier&) = delete;
  Identifier& operator=(const Identifier&) = delete;

  /// Hands a window to the worker (replaces a window still waiting).
  void submit(const MeasuredRevolution& window, std::int64_t revolution, std::int64_t utime_us);
  /// Fits what is waiting and stops the worker; later submits are ignored.
  void finish();

  /// The newest result, if any.
  [[nodiscard]] std::optional<IdentifiedWindow> latest() const;
  /// Windows fitted, and windows replaced before the worker got to them.
  [[nodiscard]] std::int64_t fitted() const;
  [[nodiscard]] std::int64_t superseded() const;

 private:
  void run();

  WindowFitter fitter_;
  Callback on_result_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::optional<MeasuredRevolution> pending_;
  std::int64_t pending_revolution_ = 0;
  std::int64_t pending_utime_us_ = 0;
  std::optional<IdentifiedWindow> latest_;
  std::int64_t fitted_ = 0;
  std::int64_t superseded_ = 0;
  bool stop_ = false;
  std::thread worker_;  // last: started once everything above exists
};

}  // namespace millwatch::identify
