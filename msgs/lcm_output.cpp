#include "msgs/lcm_output.hpp"

#include <chrono>
#include <numbers>

#include "msgs/lcm_convert.hpp"

namespace millwatch::messaging {

LcmOutput::LcmOutput(lcm::LCM& lcm, ChannelNames channels, monitor::PipelineSink* downstream)
    : lcm_(lcm),
      channels_(std::move(channels)),
      downstream_(downstream),
      thread_([this] { run(); }) {}

LcmOutput::~LcmOutput() {
  drain();
  stop_.store(true);
  signal_.fetch_add(1);
  signal_.notify_one();
  thread_.join();
}

void LcmOutput::enqueue(const Item& item) {
  if (queue_.try_push(item)) {
    queued_.fetch_add(1);
    signal_.fetch_add(1, std::memory_order_release);
    signal_.notify_one();
  } else {
    dropped_.fetch_add(1);
  }
}

void LcmOutput::on_revolution(const monitor::RevolutionRecord& r) {
  enqueue(r);
  if (downstream_ != nullptr) {
    downstream_->on_revolution(r);
  }
}

void LcmOutput::on_spindle(const monitor::SpindleUpdate& u) {
  enqueue(u);
  if (downstream_ != nullptr) {
    downstream_->on_spindle(u);
  }
}

void LcmOutput::on_alert(const monitor::Alert& a) {
  enqueue(a);
  if (downstream_ != nullptr) {
    downstream_->on_alert(a);
  }
}

void LcmOutput::on_event(const monitor::PipelineEvent& e) {
  if (downstream_ != nullptr) {
    downstream_->on_event(e);
  }
}

void LcmOutput::publish_status(const monitor::PipelineStatus& s) {
  enqueue(s);
}

void LcmOutput::on_sync_average(const monitor::SyncAverage& measured,
                                const monitor::Lockstep* model, std::int64_t revolution,
                                std::int64_t utime_us) {
  SyncSnapshot& s = sync_scratch_;
  s.utime_us = utime_us;
  s.revolution = revolution;
  s.window_revolutions = measured.revolutions();
  s.model_valid = model != nullptr;
  s.bins = std::min(measured.bins(), SyncSnapshot::kMaxBins);
  for (int b = 0; b < s.bins; ++b) {
    const auto ub = static_cast<std::size_t>(b);
    for (int a = 0; a < 3; ++a) {
      s.values[static_cast<std::size_t>(a)][ub] = measured.average(a, b);
    }
    const auto m = model != nullptr ? model->force_at(2.0 * std::numbers::pi * b / s.bins)
                                    : std::array<double, 3>{};
    for (std::size_t a = 0; a < 3; ++a) {
      s.values[3 + a][ub] = m[a];
    }
  }
  if (sync_queue_.try_push(s)) {
    queued_.fetch_add(1);
    signal_.fetch_add(1, std::memory_order_release);
    signal_.notify_one();
  } else {
    dropped_.fetch_add(1);
  }
  if (downstream_ != nullptr) {
    downstream_->on_sync_average(measured, model, revolution, utime_us);
  }
}

void LcmOutput::publish(const Item& item) {
  if (const auto* r = std::get_if<monitor::RevolutionRecord>(&item)) {
    const tooth_periods2_t t = tooth_periods(*r);
    const flute_peaks2_t p = flute_peaks(*r);
    lcm_.publish(channels_.tooth_periods, &t);
    lcm_.publish(channels_.flute_peaks, &p);
    published_ += 2;
    if (r->model_valid) {
      const model_residual_t m = model_residual(*r);
      lcm_.publish(channels_.residual, &m);
      ++published_;
    }
  } else if (const auto* u = std::get_if<monitor::SpindleUpdate>(&item)) {
    const spindle_state2_t s = spindle_state(*u);
    lcm_.publish(channels_.spindle, &s);
    ++published_;
  } else if (const auto* a = std::get_if<monitor::Alert>(&item)) {
    const tool_alert_t t = tool_alert(*a, ++alert_seq_);
    lcm_.publish(channels_.alert, &t);
    ++published_;
  } else if (const auto* st = std::get_if<monitor::PipelineStatus>(&item)) {
    const pipeline_status2_t p =
        pipeline_status(*st, ++status_seq_, published_.load(), dropped_.load());
    lcm_.publish(channels_.status, &p);
    ++published_;
  }
}

void LcmOutput::run() {
  Item item;
  SyncSnapshot snapshot;
  std::uint64_t seen = 0;
  // A backlog (the revolutions measured at once when measuring starts, ~90 messages) goes out
  // in paced bursts: LCM receivers queue 30 messages per subscription by default (lcm-logger,
  // lcm-spy) and drop the rest when their thread is slow to run. In steady state a revolution
  // is 3 messages and no burst reaches the limit.
  constexpr int kBurstMessages = 16;
  int burst = 0;
  while (true) {
    bool any = false;
    while (queue_.try_pop(item)) {
      publish(item);
      handled_.fetch_add(1);
      any = true;
      if (++burst == kBurstMessages) {
        burst = 0;
        std::this_thread::sleep_for(std::chrono::microseconds(500));
      }
    }
    if (!any) {
      burst = 0;
    }
    if (sync_queue_.try_pop(snapshot)) {
      sync_average2_t s;
      s.utime = snapshot.utime_us;
      s.revolution = snapshot.revolution;
      s.window_revolutions = snapshot.window_revolutions;
      const auto n = static_cast<std::ptrdiff_t>(snapshot.bins);
      s.fx_N.assign(snapshot.values[0].begin(), snapshot.values[0].begin() + n);
      s.fy_N.assign(snapshot.values[1].begin(), snapshot.values[1].begin() + n);
      s.fz_N.assign(snapshot.values[2].begin(), snapshot.values[2].begin() + n);
      s.model_fx_N.assign(snapshot.values[3].begin(), snapshot.values[3].begin() + n);
      s.model_fy_N.assign(snapshot.values[4].begin(), snapshot.values[4].begin() + n);
      s.model_fz_N.assign(snapshot.values[5].begin(), snapshot.values[5].begin() + n);
      s.num_bins = static_cast<std::int32_t>(s.fx_N.size());
      s.model_valid = snapshot.model_valid;
      lcm_.publish(channels_.sync_average, &s);
      ++published_;
      handled_.fetch_add(1);
      any = true;
    }
    if (any) {
      continue;
    }
    if (stop_.load()) {
      return;
    }
    // Sleep until the producer signals (or a short timeout, to notice a stop).
    const std::uint64_t now = signal_.load(std::memory_order_acquire);
    if (now == seen) {
      signal_.wait(now, std::memory_order_acquire);
    }
    seen = signal_.load(std::memory_order_acquire);
  }
}

bool LcmOutput::drain(double timeout_s) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (handled_.load() < queued_.load()) {
    if (std::chrono::steady_clock::now() > deadline) {
      return false;
    }
    signal_.fetch_add(1);
    signal_.notify_one();
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  return true;
}

}  // namespace millwatch::messaging
