#pragma once
// The live identifier's CPU budget (identification.cpu_budget): the fits use on average at most
// `fraction` of one core. After a fit that took t s of the worker's CPU time, the worker takes no
// new window for t·(1/fraction − 1) s of wall time, so that fit and rest together, t/fraction,
// hold the fraction (a fit that has the core to itself lasts about t). Windows that come
// meanwhile are skipped on purpose and counted (identify::Identifier).
//
// Pure bookkeeping on times the caller measures: the identifier passes its worker thread's CPU
// clock and the steady clock, tests their own.
//
//   CpuBudget b(0.02);
//   b.fit_done(cpu_s, now_s);   // after each fit
//   if (b.allows(now_s)) ...    // a window may be taken

namespace millwatch::identify {

class CpuBudget {
 public:
  /// @param fraction of one core, in (0, 1]; 1: no budget, never a rest.
  /// @throws std::invalid_argument outside (0, 1].
  explicit CpuBudget(double fraction = 1.0);

  /// A fit that took `cpu_s` of CPU time ended at wall time `end_s`: the rest starts.
  void fit_done(double cpu_s, double end_s);
  /// Whether a window may be taken at wall time `now_s`: the rest after the last fit is over.
  [[nodiscard]] bool allows(double now_s) const { return !(now_s < rest_until_s_); }
  /// Wall time at which the rest after the last fit ends (−∞ before the first).
  [[nodiscard]] double rest_until_s() const { return rest_until_s_; }
  /// The last fit and its rest: t/fraction, the interval between fits the budget allows (0 before
  /// the first fit).
  [[nodiscard]] double period_s() const { return period_s_; }
  [[nodiscard]] double fraction() const { return fraction_; }
  /// Whether the budget ever rests (fraction < 1).
  [[nodiscard]] bool limits() const { return fraction_ < 1.0; }

 private:
  double fraction_ = 1.0;
  double rest_until_s_;
  double period_s_ = 0.0;
};

}  // namespace millwatch::identify
