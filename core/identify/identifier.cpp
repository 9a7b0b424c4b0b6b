#include "core/identify/identifier.hpp"

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <utility>

#include "core/monitor/background_thread.hpp"

namespace millwatch::identify {
namespace {

/// Seconds on the steady clock (the budget's wall time).
double steady_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// CPU time of the calling thread, s (what the budget counts: the fit's own work, not the time
/// it waited for the core).
double thread_cpu_s() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

/// `r` with the systematic part of `s`'s estimates (same quantity) added in quadrature.
void carry_systematic(const FitResult& s, FitResult& r) {
  auto carry = [](const Estimate& from, Estimate& to) {
    if (!to.determined || !from.determined) {
      return;  // not an estimate (no σ to add to), or none to carry
    }
    to.sigma_sys = from.sigma_sys;
    to.sigma = std::hypot(to.sigma_stat, to.sigma_sys);
  };
  auto carry_named = [&](const std::vector<Estimate>& from, std::vector<Estimate>& to) {
    for (Estimate& e : to) {
      for (const Estimate& f : from) {
        if (f.name == e.name) {
          carry(f, e);
        }
      }
    }
  };
  carry(s.rho_um, r.rho_um);
  carry(s.gamma_rad, r.gamma_rad);
  carry(s.alignment_rad, r.alignment_rad);
  carry_named(s.cutting_radius_um, r.cutting_radius_um);
  carry_named(s.radius_from_ce1_um, r.radius_from_ce1_um);
  carry_named(s.coefficients, r.coefficients);
  carry_named(s.extra, r.extra);
}

}  // namespace

Identifier::Identifier(const model::ModelConfig& model, FilterResponse filter, FitOptions options,
                       Callback on_result, HandOver hand_over, double cpu_budget)
    : fitter_(model, std::move(filter), options),
      on_result_(std::move(on_result)),
      hand_over_(hand_over),
      options_(std::move(options)),
      budget_(cpu_budget),
      worker_([this] { run(); }) {}

Identifier::~Identifier() {
  finish();
}

void Identifier::submit(const MeasuredRevolution& window, std::int64_t revolution,
                        std::int64_t utime_us, std::int64_t due_revolution) {
  {
    const std::lock_guard lock(mutex_);
    if (stop_) {
      return;
    }
    if (hand_over_ == HandOver::kWhenReady && budget_.limits()) {
      // A fit in progress is followed by a rest, and the first window after the rest is fitted:
      // what comes before is not (nor copied).
      const bool fitting =
          std::any_of(queue_.begin(), queue_.end(), [](const Entry& e) { return e.fitting; });
      if (fitting || !budget_.allows(steady_s())) {
        ++skipped_for_budget_;
        return;
      }
    }
    if (hand_over_ == HandOver::kWhenReady) {
      int waiting = 0;
      for (const Entry& e : queue_) {
        waiting += !e.fitting && !e.result ? 1 : 0;
      }
      if (waiting >= kMaxWaiting) {
        for (auto it = queue_.begin(); it != queue_.end(); ++it) {
          if (!it->fitting && !it->result) {
            queue_.erase(it);
            ++superseded_;
            break;
          }
        }
      }
    }
    Entry& e = queue_.emplace_back();
    e.window = window;
    e.revolution = revolution;
    e.utime_us = utime_us;
    e.due_revolution = due_revolution;
  }
  wake_.notify_one();
}

Identifier::Entry* Identifier::front() {
  for (Entry& e : queue_) {
    if (!e.stale) {
      return &e;
    }
  }
  return nullptr;
}

std::optional<IdentifiedWindow> Identifier::take_due(std::int64_t revolution) {
  std::unique_lock lock(mutex_);
  Entry* first = front();
  if (first == nullptr || first->due_revolution > revolution) {
    return std::nullopt;
  }
  Entry& due = *first;
  if (!due.result) {
    if (hand_over_ == HandOver::kWhenReady) {
      late_ += due.counted_late ? 0 : 1;
      due.counted_late = true;
      return std::nullopt;
    }
    done_.wait(lock, [&] { return due.result.has_value() || stopped_; });
    if (!due.result) {
      return std::nullopt;
    }
  }
  std::optional<IdentifiedWindow> out = std::move(due.result);
  queue_.remove_if([&](const Entry& e) { return &e == &due; });
  return out;
}

void Identifier::restart(const model::ModelConfig& model, FilterResponse filter,
                         FitOptions options) {
  {
    const std::lock_guard lock(mutex_);
    queue_.remove_if([](const Entry& e) { return !e.fitting; });
    for (Entry& e : queue_) {
      e.stale = true;  // the one being fitted: removed when it ends
    }
    next_model_ = NextModel{model, std::move(filter), std::move(options)};
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

std::int64_t Identifier::late() const {
  const std::lock_guard lock(mutex_);
  return late_;
}

std::int64_t Identifier::skipped_for_budget() const {
  const std::lock_guard lock(mutex_);
  return skipped_for_budget_;
}

double Identifier::budget_period_s() const {
  const std::lock_guard lock(mutex_);
  return hand_over_ == HandOver::kWhenReady && budget_.limits() ? budget_.period_s() : 0.0;
}

void Identifier::set_cpu_budget(double fraction) {
  const CpuBudget next(fraction);  // throws before anything changes
  const std::lock_guard lock(mutex_);
  budget_ = next;
}

void Identifier::run() {
  monitor::make_this_thread_batch();  // a fit's wake-up does not preempt the sample thread
  std::optional<FitResult> previous;
  const auto next = [this]() -> Entry* {
    for (Entry& e : queue_) {
      if (!e.fitting && !e.result) {
        return &e;
      }
    }
    return nullptr;
  };
  for (;;) {
    Entry* entry = nullptr;
    IdentifiedWindow out;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [&] { return stop_ || next() != nullptr || next_model_.has_value(); });
      if (next_model_) {
        NextModel next_model = std::move(*next_model_);
        next_model_.reset();
        options_ = next_model.options;
        lock.unlock();
        fitter_ = WindowFitter(next_model.model, next_model.filter, options_);
        previous.reset();
        systematic_.reset();
        continue;
      }
      entry = next();
      if (entry == nullptr) {  // stopped with nothing waiting
        stopped_ = true;
        done_.notify_all();
        return;
      }
      entry->fitting = true;
      out.revolution = entry->revolution;
      out.utime_us = entry->utime_us;
      out.window_revolutions = entry->window.revolutions;
    }
    // The entry stays in the list while it is being fitted (only finished entries are taken,
    // only waiting ones dropped), and list nodes do not move.
    const double cpu0_s = thread_cpu_s();
    out.fit_started_s = steady_s();
    out.fit = fit(entry->window, previous, out.variants_fitted);
    const double end_s = steady_s();
    out.fit_cpu_seconds = thread_cpu_s() - cpu0_s;
    out.fit_seconds = end_s - out.fit_started_s;
    if (out.fit.ok) {
      previous = out.fit;
    }
    {
      const std::lock_guard lock(mutex_);
      if (hand_over_ == HandOver::kWhenReady && budget_.limits()) {
        // The rest begins: the windows that came during the fit are not fitted either.
        budget_.fit_done(out.fit_cpu_seconds, end_s);
        skipped_for_budget_ += static_cast<std::int64_t>(queue_.remove_if(
            [&](const Entry& e) { return &e != entry && !e.fitting && !e.result; }));
      }
      if (entry->stale) {  // fitted for a model replaced meanwhile
        queue_.remove_if([&](const Entry& e) { return &e == entry; });
        continue;
      }
      entry->fitting = false;
      entry->result = out;
      latest_ = out;
      ++fitted_;
    }
    done_.notify_all();
    if (on_result_) {
      on_result_(out);
    }
  }
}

}  // namespace millwatch::identify

namespace millwatch::identify {

bool runout_moved(const FitResult& before, const FitResult& now) {
  constexpr double kChiSquare2Dof3Sigma = 11.83;
  const double rho0 = before.rho_um.value, gamma0 = before.gamma_rad.value;
  const double rho1 = now.rho_um.value, gamma1 = now.gamma_rad.value;
  const double cos_turn = std::cos(gamma1 - gamma0), sin_turn = std::sin(gamma1 - gamma0);
  // now's vector in before's radial and tangential directions, minus before's (ρ0, 0).
  const double radial_um = rho1 * cos_turn - rho0;
  const double across_um = rho1 * sin_turn;
  const auto square = [](double x) { return x * x; };
  // now's variances along its own radius and across it, turned into before's directions.
  const double c2 = square(cos_turn), s2 = square(sin_turn);
  const double now_radial = square(now.rho_um.sigma);
  const double now_across = square(rho1 * now.gamma_rad.sigma);
  const double var_radial = square(before.rho_um.sigma) + c2 * now_radial + s2 * now_across;
  const double var_across =
      square(rho0 * before.gamma_rad.sigma) + s2 * now_radial + c2 * now_across;
  // A component without uncertainty (an exact fit) moved if it moved at all.
  const auto term = [&](double d, double var) {
    return var > 0.0 ? square(d) / var : (d != 0.0 ? kChiSquare2Dof3Sigma + 1.0 : 0.0);
  };
  return term(radial_um, var_radial) + term(across_um, var_across) > kChiSquare2Dof3Sigma;
}

FitResult Identifier::fit(const MeasuredRevolution& window,
                          const std::optional<FitResult>& previous, bool& variants_fitted) {
  const FitResult* seed = previous ? &*previous : nullptr;
  variants_fitted = false;
  auto with_variants = [&](const FitResult* from) {
    FitResult full = fitter_.fit(window, from);
    variants_fitted = options_.systematic && full.ok;
    if (full.ok) {
      systematic_ = full;
      since_systematic_ = 0;
    }
    return full;
  };
  if (!options_.systematic || !systematic_ || ++since_systematic_ >= kSystematicEvery) {
    return with_variants(seed);
  }
  FitResult r = fitter_.fit(window, seed, false);
  if (!r.ok) {
    return with_variants(seed);
  }
  carry_systematic(*systematic_, r);
  if (runout_moved(*systematic_, r) ||
      r.runout_at_contact_edge != systematic_->runout_at_contact_edge) {
    // The runout moved beyond both windows' uncertainty since the variants were fitted, or the
    // fit went onto a flute's contact edge or off it (the spread of the variants off an edge says
    // nothing of it on one, and back): fit them again, from this window's own result (the main
    // fit then starts where it ends).
    return with_variants(&r);
  }
  return r;
}

}  // namespace millwatch::identify
