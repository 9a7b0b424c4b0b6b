#include "msgs/lcm_output.hpp"

#include <pthread.h>

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

void LcmOutput::wake_if_asleep() {
  // Pairs with the fence in run(): either the publisher sees what was just queued, or this sees
  // it asleep and wakes it.
  std::atomic_thread_fence(std::memory_order_seq_cst);
  if (asleep_.load(std::memory_order_relaxed)) {
    signal_.fetch_add(1, std::memory_order_release);
    signal_.notify_one();
  }
}

void LcmOutput::enqueue(const Item& item) {
  if (queue_.try_push(item)) {
    queued_.fetch_add(1);
    wake_if_asleep();
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
    wake_if_asleep();
  } else {
    dropped_.fetch_add(1);
  }
  if (downstream_ != nullptr) {
    downstream_->on_sync_average(measured, model, revolution, utime_us);
  }
}

template <class Message>
bool LcmOutput::send(const std::string& channel, const Message& message) {
  // Not lcm::LCM::publish: it allocates a buffer per message and ignores encode()'s result.
  const int size = message.getEncodedSize();
  if (size < 0) {
    dropped_.fetch_add(1);
    return false;
  }
  if (buffer_.size() < static_cast<std::size_t>(size)) {
    buffer_.resize(static_cast<std::size_t>(size));
  }
  if (message.encode(buffer_.data(), 0, size) != size ||
      lcm_publish(lcm_.getUnderlyingLCM(), channel.c_str(), buffer_.data(),
                  static_cast<unsigned int>(size)) != 0) {
    dropped_.fetch_add(1);
    return false;
  }
  published_.fetch_add(1);
  return true;
}

void LcmOutput::publish(const Item& item) {
  if (const auto* r = std::get_if<monitor::RevolutionRecord>(&item)) {
    send(channels_.tooth_periods, tooth_periods(*r));
    if (r->measured.bounded) {  // flute windows known; otherwise no peak was measured
      send(channels_.flute_peaks, flute_peaks(*r));
    }
    if (r->model_valid) {
      send(channels_.residual, model_residual(*r));
    }
  } else if (const auto* u = std::get_if<monitor::SpindleUpdate>(&item)) {
    send(channels_.spindle, spindle_state(*u));
  } else if (const auto* a = std::get_if<monitor::Alert>(&item)) {
    send(channels_.alert, tool_alert(*a, ++alert_seq_));
  } else if (const auto* st = std::get_if<monitor::PipelineStatus>(&item)) {
    send(channels_.status, pipeline_status(*st, ++status_seq_, published_.load(), dropped_.load()));
  }
}

void LcmOutput::run() {
  pthread_setname_np(pthread_self(), "mw-publish");  // for top -H and scripts/daemon_load.sh
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
      sync_average2_t& s = sync_message_;
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
      send(channels_.sync_average, s);
      handled_.fetch_add(1);
      any = true;
    }
    if (any) {
      // What comes in the next kPace goes out in one round, without a wake-up per output.
      std::this_thread::sleep_for(kPace);
      continue;
    }
    if (stop_.load()) {
      return;
    }
    // Nothing to do: asleep until the producer signals (a stop or a drain signals too).
    asleep_.store(true, std::memory_order_relaxed);
    std::atomic_thread_fence(std::memory_order_seq_cst);  // pairs with wake_if_asleep()
    const std::uint64_t now = signal_.load(std::memory_order_acquire);
    if (now == seen && queue_.empty() && sync_queue_.empty() && !stop_.load()) {
      signal_.wait(now, std::memory_order_acquire);
    }
    asleep_.store(false, std::memory_order_relaxed);
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
