// Throughput and latency of the whole monitoring pipeline, lockstep model on, on a simulated
// recording of [000]'s cut (3 channels).
//
//   build/release/bench/pipeline_benchmark

#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <thread>
#include <vector>

#include "core/identify/identifier.hpp"
#include "core/monitor/pipeline.hpp"
#include "core/sim/cut_simulator.hpp"

namespace {

using namespace millwatch;

struct Recording {
  double sample_rate_hz = 0.0;
  std::vector<double> t, fx, fy, fz;
};

Recording make_recording(double sample_rate_hz, double duration_s) {
  sim::Scenario s;
  s.sample_rate_hz = sample_rate_hz;
  s.duration_s = duration_s;
  s.spindle.actual_rpm = 25252.0;
  s.noise.enabled = true;
  s.quantisation.enabled = true;
  sim::CutSimulator sim(s);
  Recording r;
  r.sample_rate_hz = sample_rate_hz;
  const auto n = static_cast<std::size_t>(sim.total_samples());
  r.t.resize(n);
  r.fx.resize(n);
  r.fy.resize(n);
  r.fz.resize(n);
  sim.next_block(r.t, r.fx, r.fy, r.fz);
  return r;
}

/// Measures the time from the last sample of a revolution (the block that completes it) to the
/// revolution's record.
struct LatencySink : monitor::PipelineSink {
  std::chrono::steady_clock::time_point block_start{};
  std::vector<double>* latencies_s = nullptr;
  void on_revolution(const monitor::RevolutionRecord& /*r*/) override {
    latencies_s->push_back(
        std::chrono::duration<double>(std::chrono::steady_clock::now() - block_start).count());
  }
};

/// Steady state: the first half second (lock, model build, valley template) is not timed.
void BM_Pipeline(benchmark::State& state) {
  const double fs = static_cast<double>(state.range(0));
  const std::size_t block = static_cast<std::size_t>(state.range(1));
  const Recording r = make_recording(fs, 2.5);
  monitor::MonitorConfig c;
  c.sample_rate_hz = fs;
  c.lockstep = state.range(2) != 0;
  double processed_s = 0.0;
  std::vector<double> latencies_s;
  latencies_s.reserve(1 << 20);
  const auto start = static_cast<std::size_t>(0.5 * fs) / block * block;
  auto feed = [&](monitor::Pipeline& p, LatencySink& sink, std::size_t from, std::size_t to) {
    for (std::size_t i = from; i < to; i += block) {
      const std::size_t n = std::min(block, to - i);
      sink.block_start = std::chrono::steady_clock::now();
      p.process({std::llround(r.t[i] * 1e6), 0, fs, std::span(r.fx).subspan(i, n),
                 std::span(r.fy).subspan(i, n), std::span(r.fz).subspan(i, n)});
    }
  };
  for (auto _ : state) {
    state.PauseTiming();
    std::vector<double> warm_up_s;
    LatencySink sink;
    sink.latencies_s = &warm_up_s;
    monitor::Pipeline p(c, sink);
    feed(p, sink, 0, start);
    sink.latencies_s = &latencies_s;
    state.ResumeTiming();
    feed(p, sink, start, r.t.size());
    processed_s += static_cast<double>(r.t.size() - start) / fs;
  }
  state.counters["x_realtime"] = benchmark::Counter(processed_s, benchmark::Counter::kIsRate);
  // Wall-clock latencies: the worst includes whatever else the machine did (preemption); the
  // 99th percentile is the pipeline's own.
  std::sort(latencies_s.begin(), latencies_s.end());
  const auto n = latencies_s.size();
  double sum_s = 0.0;
  for (const double l : latencies_s) {
    sum_s += l;
  }
  state.counters["latency_mean_us"] = n > 0 ? 1e6 * sum_s / static_cast<double>(n) : 0.0;
  state.counters["latency_p99_us"] = n > 0 ? 1e6 * latencies_s[n * 99 / 100] : 0.0;
  state.counters["latency_worst_us"] = n > 0 ? 1e6 * latencies_s.back() : 0.0;
  state.SetItemsProcessed(static_cast<std::int64_t>(r.t.size() - start) * state.iterations());
}
// Blocks of 1 ms at each rate (a DAQ bridge's typical message); lockstep model on (1) or off (0:
// the steps bench/reference_pipeline.py does, and the synchronous average and alerts).
BENCHMARK(BM_Pipeline)
    ->Args({50000, 50, 1})
    ->Args({333300, 333, 1})
    ->Args({50000, 50, 0})
    ->Args({333300, 333, 0})
    ->Unit(benchmark::kMillisecond);

/// The daemon's sample thread at 333.3 kHz while identification runs in its worker thread (live
/// hand-over: never waits): throughput of the sample thread with a fit in progress most of the
/// time, and what the worker kept up with (windows fitted, dropped, results late, taken).
void BM_PipelineWithIdentification(benchmark::State& state) {
  const double fs = 333300.0;
  const std::size_t block = 333;
  const Recording r = make_recording(fs, 2.5);
  monitor::MonitorConfig c;
  c.sample_rate_hz = fs;
  double processed_s = 0.0;
  std::int64_t fitted = 0, dropped = 0, late = 0, taken = 0;
  for (auto _ : state) {
    state.PauseTiming();
    monitor::PipelineSink sink;
    monitor::Pipeline p(c, sink);
    const signal::ButterworthDesign filter = p.filter();
    identify::Identifier id(
        c.model, [filter](double hz) { return filter.response(hz); }, identify::FitOptions{},
        nullptr, identify::HandOver::kWhenReady);
    p.attach_identifier(&id);
    state.ResumeTiming();
    for (std::size_t i = 0; i < r.t.size(); i += block) {
      const std::size_t n = std::min(block, r.t.size() - i);
      p.process({std::llround(r.t[i] * 1e6), 0, fs, std::span(r.fx).subspan(i, n),
                 std::span(r.fy).subspan(i, n), std::span(r.fz).subspan(i, n)});
    }
    state.PauseTiming();
    processed_s += static_cast<double>(r.t.size()) / fs;
    p.attach_identifier(nullptr);
    id.finish();
    fitted += id.fitted();
    dropped += id.superseded();
    late += id.late();
    taken += p.status().identifications_taken;
    state.ResumeTiming();
  }
  state.counters["x_realtime"] = benchmark::Counter(processed_s, benchmark::Counter::kIsRate);
  const auto per_run = [&](std::int64_t x) {
    return static_cast<double>(x) / static_cast<double>(state.iterations());
  };
  state.counters["windows_fitted"] = per_run(fitted);
  state.counters["windows_dropped"] = per_run(dropped);
  state.counters["results_late"] = per_run(late);
  state.counters["taken"] = per_run(taken);
}
BENCHMARK(BM_PipelineWithIdentification)->Unit(benchmark::kMillisecond)->Iterations(2);

/// CPU time (s) of the whole process (every thread) or of the calling thread.
double cpu_s(int who) {
  rusage u{};
  getrusage(who, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

/// The daemon's load at 333.3 kHz with identification running, as live: blocks of 1 ms fed at
/// real time (paced by the clock) to the pipeline with the identifier's worker attached (live
/// hand-over), CPU time from getrusage over the run, per second of signal (1 = a whole core):
/// the sample thread alone, and the process (sample thread and worker), from 0.5 s on (after the
/// lock and the model build). Without the daemon's
/// LCM receive and publish (a few per cent of the sample thread's work).
void BM_DaemonLoadRealTime(benchmark::State& state) {
  const double fs = 333300.0;
  const std::size_t block = 333;
  const Recording r = make_recording(fs, 3.0);
  monitor::MonitorConfig c;
  c.sample_rate_hz = fs;
  double signal_s = 0.0, process_s = 0.0, thread_s = 0.0;
  std::int64_t fitted = 0, dropped = 0;
  for (auto _ : state) {
    monitor::PipelineSink sink;
    monitor::Pipeline p(c, sink);
    const signal::ButterworthDesign filter = p.filter();
    identify::Identifier id(
        c.model, [filter](double hz) { return filter.response(hz); }, identify::FitOptions{},
        nullptr, identify::HandOver::kWhenReady);
    p.attach_identifier(&id);
    // Timed from 0.5 s on (the lock and the model build before it happen once).
    const std::size_t steady = static_cast<std::size_t>(0.5 * fs) / block * block;
    double process0 = 0.0, thread0 = 0.0;
    const auto start = std::chrono::steady_clock::now();
    for (std::size_t i = 0; i < r.t.size(); i += block) {
      std::this_thread::sleep_until(start + std::chrono::duration<double>(r.t[i]));
      if (i == steady) {
        process0 = cpu_s(RUSAGE_SELF);
        thread0 = cpu_s(RUSAGE_THREAD);
      }
      const std::size_t n = std::min(block, r.t.size() - i);
      p.process({std::llround(r.t[i] * 1e6), 0, fs, std::span(r.fx).subspan(i, n),
                 std::span(r.fy).subspan(i, n), std::span(r.fz).subspan(i, n)});
    }
    process_s += cpu_s(RUSAGE_SELF) - process0;  // the worker's fits so far included
    thread_s += cpu_s(RUSAGE_THREAD) - thread0;
    signal_s += static_cast<double>(r.t.size() - steady) / fs;
    p.attach_identifier(nullptr);
    id.finish();
    fitted += id.fitted();
    dropped += id.superseded();
  }
  state.counters["sample_thread_of_a_core"] = thread_s / signal_s;
  state.counters["process_of_a_core"] = process_s / signal_s;
  state.counters["windows_fitted"] = static_cast<double>(fitted);
  state.counters["windows_dropped"] = static_cast<double>(dropped);
}
BENCHMARK(BM_DaemonLoadRealTime)->Unit(benchmark::kMillisecond)->Iterations(1)->UseRealTime();

/// What a new lock costs once: building the lockstep model at the measured speed.
void BM_LockstepModelBuild(benchmark::State& state) {
  monitor::MonitorConfig c;
  const auto filter = signal::ButterworthDesign::lowpass(50000.0, 3300.0, 4);
  double hz = 25252.0 / 60.0;
  for (auto _ : state) {
    monitor::Lockstep l(c.model, filter);
    l.set_spindle_hz(hz);
    hz *= 1.0001;
  }
}
BENCHMARK(BM_LockstepModelBuild)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
