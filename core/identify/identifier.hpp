#pragma once
// Continuous identification: the monitor's synchronous-average windows are fitted in a worker
// thread, never in the caller's (the sample thread only copies a window and signals), each
// seeded with the previous result.
//
// Hand-over on a schedule. Each window is submitted with the revolution at which its result is
// due (the pipeline: its end plus a fixed lag). take_due(revolution) hands over the oldest result
// whose due revolution has come — always at that revolution in a replay (HandOver::kWait: the
// caller waits for the fit, so a replay is deterministic), and live (kWhenReady) at that
// revolution when the fit is done in time, else at the first call after it is done, counted as
// late. Live and replay therefore agree revolution by revolution whenever no result was late.
// Live, a worker that falls behind drops the oldest window still waiting (counted as superseded)
// rather than let the queue grow.
//
// CPU budget (live only; identification.cpu_budget, identify::CpuBudget). After a fit that took
// t s of the worker's CPU time (its thread's clock, not the wall clock), the worker takes no new
// window for t·(1/budget − 1) s of wall time: windows submitted during the fit or the rest are
// not fitted (nor copied), counted as skipped for the budget, and nothing is superseded. The
// first window submitted after the rest is fitted. submitted = fitted + superseded + skipped for
// the budget
// (+ the ones a restart() or finish() dropped, + the ones still queued). A replay (kWait) waits
// for every fit and ignores the budget.
//
// Cost. The systematic part of the uncertainty (the spread over model variants, window_fit.hpp)
// costs several refits; the model's discrepancy changes slowly, so it is re-estimated on the
// first window, every kSystematicEvery windows and whenever the runout moved by more than the
// two fits' noise explains (runout_moved()), and carried over (per parameter) in between.
//
//   Identifier id(model, filter, options, publish, HandOver::kWhenReady, 0.02);
//   id.submit(window, revolution, utime_us, due_revolution);  // sample thread: a copy, no fit
//   if (auto w = id.take_due(revolution)) use(*w);            // sample thread, per revolution
//   id.finish();                                              // fits what is waiting, stops

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <list>
#include <mutex>
#include <optional>
#include <thread>
#include <utility>

#include "core/identify/cpu_budget.hpp"
#include "core/identify/window_fit.hpp"

namespace millwatch::identify {

/// One fitted window.
struct IdentifiedWindow {
  FitResult fit;
  std::int64_t revolution = 0;  ///< last revolution of the window
  std::int64_t utime_us = 0;    ///< its end
  int window_revolutions = 0;
  double fit_seconds = 0.0;      ///< wall-clock time the fit took
  double fit_cpu_seconds = 0.0;  ///< the worker thread's CPU time for it (what the budget counts)
  double fit_started_s = 0.0;    ///< steady-clock time (s since its epoch) the fit began
  bool variants_fitted = false;  ///< the systematic variants were fitted on this window (else
                                 ///< their σ_sys carried over from the last window that had them)
};

/// Whether the runout of `now` differs from that of `before` by more than the two fits'
/// uncertainty explains: the difference of the runout vectors ρ·e^{iγ}, radial and across
/// `before`'s, each against the sum of both fits' variances there (σ_ρ² along a fit's radius,
/// (ρ·σ_γ)² across it, `now`'s turned by the angle between them), the two summed, beyond χ²'s
/// 99.73 % point with two degrees of freedom (11.83: a 3σ move). Two windows of a steady cut
/// differ by about √2 times one fit's σ in each direction, so a test against one σ fires on most
/// of them. σ as reported, its systematic part included: the identifier refits the variants to
/// follow a change of the operating point, and a move the reported σ cannot resolve changes their
/// spread by a small part of itself (statistical σ alone also missed the fit's own wander between
/// windows, about twice it on exact windows with little noise).
[[nodiscard]] bool runout_moved(const FitResult& before, const FitResult& now);

/// How take_due() treats a result whose fit is still running when it is due.
enum class HandOver {
  kWait,       ///< wait for it (replay: deterministic)
  kWhenReady,  ///< never wait; hand it over when done, counted as late (live)
};

class Identifier {
 public:
  using Callback = std::function<void(const IdentifiedWindow&)>;

  /// @param on_result called in the worker thread after each fit
  /// @param cpu_budget fraction of one core the fits may use on average, in (0, 1] (1: none);
  /// kWhenReady only (see CPU budget above). @throws std::invalid_argument outside (0, 1].
  Identifier(const model::ModelConfig& model, FilterResponse filter, FitOptions options,
             Callback on_result, HandOver hand_over = HandOver::kWhenReady,
             double cpu_budget = 1.0);
  ~Identifier();
  Identifier(const Identifier&) = delete;
  Identifier& operator=(const Identifier&) = delete;

  /// Queues a window (ending at `revolution`) whose result is due at `due_revolution`; during a
  /// budget's rest, counts it as skipped instead.
  void submit(const MeasuredRevolution& window, std::int64_t revolution, std::int64_t utime_us,
              std::int64_t due_revolution);
  /// The oldest result due at or before `revolution`, if any (see HandOver).
  std::optional<IdentifiedWindow> take_due(std::int64_t revolution);
  /// A new model (a reconfiguration): windows still waiting are dropped, the fit in progress is
  /// discarded, and the worker fits later windows with the new model. Does not wait.
  void restart(const model::ModelConfig& model, FilterResponse filter, FitOptions options);
  /// Fits what is waiting and stops the worker; later submits are ignored.
  void finish();
  /// A new CPU budget (a reconfiguration): a rest in progress ends, the next fit's end starts
  /// one by the new budget. @throws std::invalid_argument outside (0, 1].
  void set_cpu_budget(double fraction);

  /// The newest result, if any.
  [[nodiscard]] std::optional<IdentifiedWindow> latest() const;
  /// Windows fitted; windows dropped before the worker got to them; results handed over after
  /// their due revolution.
  [[nodiscard]] std::int64_t fitted() const;
  [[nodiscard]] std::int64_t superseded() const;
  [[nodiscard]] std::int64_t late() const;
  /// Windows not fitted on purpose: submitted during a fit or the budget's rest after it (or,
  /// rarely, queued beside the window the worker took).
  [[nodiscard]] std::int64_t skipped_for_budget() const;
  /// The interval between fits the budget allows, the last fit's CPU time over the budget; 0 when
  /// no budget applies (kWait, a budget of 1, no fit yet). EstimateWatch's pace.
  [[nodiscard]] double budget_period_s() const;

 private:
  struct Entry {
    MeasuredRevolution window;
    std::int64_t revolution = 0;
    std::int64_t utime_us = 0;
    std::int64_t due_revolution = 0;
    bool fitting = false;
    bool counted_late = false;
    bool stale = false;  // submitted for a model replaced since: never handed over
    std::optional<IdentifiedWindow> result;
  };
  /// Windows still waiting in a live queue before the oldest is dropped.
  static constexpr int kMaxWaiting = 2;
  static constexpr int kSystematicEvery = 10;

  void run();
  /// Fits one window, with or without the systematic variants (see Cost above).
  FitResult fit(const MeasuredRevolution& window, const std::optional<FitResult>& previous,
                bool& variants_fitted);
  /// The first entry that may be handed over (not stale), or null.
  Entry* front();

  WindowFitter fitter_;                  // the worker's
  std::optional<FitResult> systematic_;  // the last fit with them
  int since_systematic_ = 0;
  struct NextModel {
    model::ModelConfig model;
    FilterResponse filter;
    FitOptions options;
  };
  std::optional<NextModel> next_model_;  // restart()
  Callback on_result_;
  HandOver hand_over_;
  mutable std::mutex mutex_;
  FitOptions options_;
  std::condition_variable wake_;  // the worker: a window came, a new model, or stop
  std::condition_variable done_;  // take_due(): a fit ended
  std::list<Entry> queue_;        // in submission order; list: the worker holds a reference
  std::optional<IdentifiedWindow> latest_;
  std::int64_t fitted_ = 0;
  std::int64_t superseded_ = 0;
  std::int64_t late_ = 0;
  std::int64_t skipped_for_budget_ = 0;
  CpuBudget budget_;  // kWhenReady only
  bool stop_ = false;
  bool stopped_ = false;  // the worker has returned
  std::thread worker_;    // last: started once everything above exists
};

}  // namespace millwatch::identify
