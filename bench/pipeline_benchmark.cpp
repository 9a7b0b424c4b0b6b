// Throughput and latency of the whole monitoring pipeline, lockstep model on, on a simulated
// recording of [000]'s cut (3 channels).
//
//   build/release/bench/pipeline_benchmark
//
// Profiling BM_Pipeline's timed part alone (the recording's simulation and the warm-up's lock
// and model build take most of the process's time): with MW_PERF_CONTROL naming perf's control
// and acknowledgement FIFOs, perf is switched on for each timed part and off after it.
//
//   cd build/release && mkfifo /tmp/perf.ctl /tmp/perf.ack
//   export MW_PERF_CONTROL=/tmp/perf.ctl,/tmp/perf.ack
//   perf record -D -1 --control fifo:$MW_PERF_CONTROL -e cpu-clock bench/pipeline_benchmark
//   (one case: --benchmark_filter=BM_Pipeline/50000/50/1)

#include <benchmark/benchmark.h>
#include <fcntl.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "bench/benchmark_cut.hpp"
#include "core/identify/identifier.hpp"
#include "core/monitor/pipeline.hpp"
#include "core/signal/butterworth_lowpass.hpp"
#include "core/signal/cpu_features.hpp"
#include "core/signal/grid_lowpass.hpp"
#include "daemon/daemon_config.hpp"

namespace {

using namespace millwatch;

using Recording = bench::BenchmarkCut;

Recording make_recording(double sample_rate_hz, double duration_s, double rpm = 25252.0) {
  return bench::simulate_benchmark_cut(sample_rate_hz, duration_s, rpm);
}

/// The time stamp (µs) of each block of `block` samples, block k's at sample k·block: what a
/// source hands over with the block (an LCM message's utime, the CSV reader's), computed before
/// the timed part — read from the recording's time column at every block, the column's cache
/// misses were ~3 % of the 50 kHz pipeline's time.
std::vector<std::int64_t> block_utimes_us(const Recording& r, std::size_t block) {
  std::vector<std::int64_t> out;
  for (std::size_t i = 0; i < r.t.size(); i += block) {
    out.push_back(std::llround(r.t[i] * 1e6));
  }
  return out;
}

/// The mean, 99th percentile and worst of `durations_s` (sorted in place) as the counters
/// <prefix>_mean_us, <prefix>_p99_us and <prefix>_worst_us (0 when there are none).
void count_durations(benchmark::State& state, const std::string& prefix,
                     std::vector<double>& durations_s) {
  std::sort(durations_s.begin(), durations_s.end());
  const auto n = durations_s.size();
  double sum_s = 0.0;
  for (const double d : durations_s) {
    sum_s += d;
  }
  state.counters[prefix + "_mean_us"] = n > 0 ? 1e6 * sum_s / static_cast<double>(n) : 0.0;
  state.counters[prefix + "_p99_us"] = n > 0 ? 1e6 * durations_s[n * 99 / 100] : 0.0;
  state.counters[prefix + "_worst_us"] = n > 0 ? 1e6 * durations_s.back() : 0.0;
}

/// Measures the time from the last sample of a revolution (the block that completes it) to the
/// revolution's record.
struct LatencySink : monitor::PipelineSink {
  std::chrono::steady_clock::time_point block_start{};
  std::vector<double>* latencies_s = nullptr;
  void on_revolution(const monitor::RevolutionRecord& /*r*/) override {
    if (latencies_s != nullptr) {
      latencies_s->push_back(
          std::chrono::duration<double>(std::chrono::steady_clock::now() - block_start).count());
    }
  }
};

/// perf's control FIFOs, named by MW_PERF_CONTROL as CTL[,ACK] (unset: nothing to switch).
/// With ACK, each switch waits for perf's "ack"; without, 30 ms, which a loaded machine may
/// outlast. A FIFO that cannot be opened (no perf reading it) is said and switches nothing.
class PerfControl {
 public:
  PerfControl() {
    const char* spec = std::getenv("MW_PERF_CONTROL");
    if (spec == nullptr) {
      return;
    }
    const std::string fifos(spec);
    const std::size_t comma = fifos.find(',');
    const std::string ctl = fifos.substr(0, comma);
    ctl_ = ::open(ctl.c_str(), O_WRONLY | O_NONBLOCK);  // fails at once when nothing reads it
    if (ctl_ < 0) {
      std::fprintf(stderr, "MW_PERF_CONTROL: cannot write to %s (%s); perf is not switched\n",
                   ctl.c_str(), std::strerror(errno));
      return;
    }
    if (comma != std::string::npos) {
      const std::string ack = fifos.substr(comma + 1);
      ack_ = ::open(ack.c_str(), O_RDONLY);
      if (ack_ < 0) {
        std::fprintf(stderr, "MW_PERF_CONTROL: cannot read %s (%s); waiting 30 ms a switch\n",
                     ack.c_str(), std::strerror(errno));
      }
    }
  }
  ~PerfControl() {
    for (const int fd : {ctl_, ack_}) {
      if (fd >= 0) {
        ::close(fd);
      }
    }
  }
  PerfControl(const PerfControl&) = delete;
  PerfControl& operator=(const PerfControl&) = delete;

  void enable() const { send("enable\n"); }
  void disable() const { send("disable\n"); }

 private:
  void send(const char* command) const {
    if (ctl_ < 0 || ::write(ctl_, command, std::strlen(command)) < 0) {
      return;
    }
    std::array<char, 16> answer{};
    if (ack_ < 0 || ::read(ack_, answer.data(), answer.size()) <= 0) {
      // perf reads the FIFO in its own time: the switch must land before the work it bounds.
      std::this_thread::sleep_for(std::chrono::milliseconds(30));
    }
  }
  int ctl_ = -1;
  int ack_ = -1;
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
  const std::vector<std::int64_t> utime_us = block_utimes_us(r, block);
  // Blocks from sample `from` to `to`; with `clocked`, each block's start time for the latency
  // of the revolutions it completes.
  auto feed = [&](monitor::Pipeline& p, LatencySink& sink, std::size_t from, std::size_t to,
                  bool clocked) {
    for (std::size_t i = from; i < to; i += block) {
      const std::size_t n = std::min(block, to - i);
      if (clocked) {
        sink.block_start = std::chrono::steady_clock::now();
      }
      p.process({utime_us[i / block], 0, fs, std::span(r.fx).subspan(i, n),
                 std::span(r.fy).subspan(i, n), std::span(r.fz).subspan(i, n)});
    }
  };
  static const PerfControl perf;  // once per process: the FIFOs stay open
  LatencySink sink;
  // Made and destroyed outside the timed part: tearing a pipeline down (its workspaces, its
  // model builder's thread) had been about 2.5 % of the timed part's profile, and a stream is
  // not torn down once a recording's worth.
  std::optional<monitor::Pipeline> p;
  // The timed part reads no clock: a clock read per block (1,000 a second of signal) had been
  // 2 % of its profile, the benchmark's cost, not the pipeline's.
  for (auto _ : state) {
    state.PauseTiming();
    perf.disable();  // the last iteration's timed part is over
    p.reset();
    p.emplace(c, sink);
    feed(*p, sink, 0, start, false);
    perf.enable();
    state.ResumeTiming();
    feed(*p, sink, start, r.t.size(), false);
    processed_s += static_cast<double>(r.t.size() - start) / fs;
  }
  perf.disable();
  p.reset();  // the timer stopped with the loop
  state.counters["x_realtime"] = benchmark::Counter(processed_s, benchmark::Counter::kIsRate);
  // Wall-clock latencies, after the timed part, over as many passes of the recording as it
  // timed (as many revolutions as when they were read in it): the worst includes whatever else
  // the machine did (preemption); the 99th percentile is the pipeline's own.
  for (std::int64_t pass = 0; pass < state.iterations(); ++pass) {
    p.emplace(c, sink);
    feed(*p, sink, 0, start, false);
    sink.latencies_s = &latencies_s;
    feed(*p, sink, start, r.t.size(), true);
    sink.latencies_s = nullptr;
    p.reset();
  }
  count_durations(state, "latency", latencies_s);
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

/// Revolution latency at 333.3 kHz while the lockstep model follows a speed ramp (25,000 →
/// 26,000 rpm over 1.5 s: a rebuild every 0.2 %, ~50 rpm, about 20 in all), blocks of 1 ms
/// handed over at real time as a live source does (paced by the clock: the model builds off the
/// sample thread have the time they have live). The default model ([000]'s effects: ~4.7 ms a
/// build here). Counters: the latencies from 0.4 s on, and the model's builds.
void BM_PipelineLatencyThroughARamp(benchmark::State& state) {
  const double fs = 333300.0;
  const std::size_t block = 333;
  sim::Scenario s = bench::benchmark_scenario(fs, 2.5, 25000.0);
  s.spindle.profile = sim::SpindleProfileKind::kRamp;
  s.spindle.ramp_end_rpm = 26000.0;
  s.spindle.ramp_start_s = 0.5;
  s.spindle.ramp_end_s = 2.0;
  const Recording r = bench::simulate_cut(s);
  const std::size_t n = r.t.size();
  const std::vector<std::int64_t> utime_us = block_utimes_us(r, block);
  monitor::MonitorConfig c;
  c.sample_rate_hz = fs;
  c.model.process.spindle_rpm = 25000.0;
  std::vector<double> latencies_s;
  latencies_s.reserve(1 << 16);
  std::int64_t builds = 0;
  // The lock and its burst of revolutions measured back to the start of the cut come first:
  // latencies from 0.4 s on, before the ramp.
  const auto steady = static_cast<std::size_t>(0.4 * fs) / block * block;
  for (auto _ : state) {
    std::vector<double> warm_up_s;
    LatencySink sink;
    sink.latencies_s = &warm_up_s;
    monitor::Pipeline p(c, sink);
    const auto start = std::chrono::steady_clock::now();
    for (std::size_t i = 0; i < n; i += block) {
      const std::size_t count = std::min(block, n - i);
      if (i == steady) {
        sink.latencies_s = &latencies_s;
      }
      std::this_thread::sleep_until(
          start + std::chrono::duration<double>(static_cast<double>(i + count) / fs));
      sink.block_start = std::chrono::steady_clock::now();
      p.process({utime_us[i / block], 0, fs, std::span(r.fx).subspan(i, count),
                 std::span(r.fy).subspan(i, count), std::span(r.fz).subspan(i, count)});
    }
    builds += p.status().model_builds;
  }
  count_durations(state, "latency", latencies_s);
  state.counters["model_builds"] =
      static_cast<double>(builds) / static_cast<double>(state.iterations());
}
BENCHMARK(BM_PipelineLatencyThroughARamp)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->UseRealTime();

/// The daemon's sample thread at 333.3 kHz while identification runs in its worker thread (live
/// hand-over: never waits): throughput of the sample thread with a fit in progress most of the
/// time, and what the worker kept up with (windows fitted, dropped, results late, taken).
void BM_PipelineWithIdentification(benchmark::State& state) {
  const double fs = 333300.0;
  const std::size_t block = 333;
  const Recording r = make_recording(fs, 2.5);
  const std::vector<std::int64_t> utime_us = block_utimes_us(r, block);
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
      p.process({utime_us[i / block], 0, fs, std::span(r.fx).subspan(i, n),
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

/// The daemon's load at 333.3 kHz with identification running, as live: blocks of 1 ms arriving
/// at real time (paced by the clock) and taken in millwatchd's rounds (an LCM source's
/// source.wake_period_s, 5 ms by default: the blocks that arrived since the last round), fed to
/// the pipeline with the identifier's worker attached (live hand-over) under
/// identification.cpu_budget (arg 1: the configuration's default when 0, else per mille; 1000 =
/// no budget). CPU time from getrusage, per second of signal (1 = a whole core): the sample
/// thread alone, and the process (sample thread and worker), from 0.5 s on (after the lock and
/// the model build) for arg 0 seconds of signal. A budget of b fits one window per t/b (t ≈ 0.4 s
/// of CPU a fit): the run must span several such periods, so the recording's last ~2.5 s are fed
/// again and again — at 25,250 rpm a revolution is 792 samples exactly, so the loop joins
/// without a phase step and the spindle stays locked. Without the daemon's LCM receive and
/// publisher threads (about as much again: scripts/daemon_load.sh measures millwatchd whole).
void BM_DaemonLoadRealTime(benchmark::State& state) {
  const double fs = 333300.0;
  const std::size_t block = 333;
  const double horizon_s = static_cast<double>(state.range(0));
  const Recording r = make_recording(fs, 3.0, 25250.0);
  const std::size_t n = r.t.size();
  constexpr std::size_t kRevolution = 792;  // samples at 25,250 rpm
  const std::size_t loop_from =
      n - (n - static_cast<std::size_t>(0.5 * fs)) / kRevolution * kRevolution;
  monitor::MonitorConfig c;
  c.sample_rate_hz = fs;
  c.model.process.spindle_rpm = 25250.0;
  const double budget =
      state.range(1) == 0 ? c.identification.cpu_budget : static_cast<double>(state.range(1)) / 1e3;
  const double wake_period_s = daemon::SourceConfig{}.wake_period_s;
  double signal_s = 0.0, process_s = 0.0, thread_s = 0.0;
  std::int64_t fitted = 0, dropped = 0, skipped = 0;
  std::vector<double> fx(block), fy(block), fz(block);
  for (auto _ : state) {
    monitor::PipelineSink sink;
    monitor::Pipeline p(c, sink);
    const signal::ButterworthDesign filter = p.filter();
    identify::Identifier id(
        c.model, [filter](double hz) { return filter.response(hz); }, identify::FitOptions{},
        nullptr, identify::HandOver::kWhenReady, budget);
    p.attach_identifier(&id);
    // Timed from 0.5 s on (the lock and the model build before it happen once).
    const auto steady = static_cast<std::size_t>(0.5 * fs) / block * block;
    const auto total = static_cast<std::size_t>((0.5 + horizon_s) * fs) / block * block;
    double process0 = 0.0, thread0 = 0.0;
    const auto start = std::chrono::steady_clock::now();
    for (std::size_t g = 0; g < total; g += block) {  // g: samples since the start
      // The round after the block's arrival (no sleep while a round's blocks are taken).
      const double arrival_s = static_cast<double>(g + block) / fs;
      const double round_s = wake_period_s > 0.0
                                 ? std::ceil(arrival_s / wake_period_s) * wake_period_s
                                 : arrival_s;  // 0: woken for every block
      std::this_thread::sleep_until(start + std::chrono::duration<double>(round_s));
      if (g == steady) {
        process0 = cpu_s(RUSAGE_SELF);
        thread0 = cpu_s(RUSAGE_THREAD);
      }
      for (std::size_t k = 0; k < block; ++k) {  // the block, as the daemon takes it off its queue
        const std::size_t s = g + k < n ? g + k : loop_from + (g + k - n) % (n - loop_from);
        fx[k] = r.fx[s];
        fy[k] = r.fy[s];
        fz[k] = r.fz[s];
      }
      p.process({std::llround(static_cast<double>(g) / fs * 1e6), 0, fs, fx, fy, fz});
    }
    process_s += cpu_s(RUSAGE_SELF) - process0;  // the worker's fits so far included
    thread_s += cpu_s(RUSAGE_THREAD) - thread0;
    signal_s += static_cast<double>(total - steady) / fs;
    p.attach_identifier(nullptr);
    id.finish();
    fitted += id.fitted();
    dropped += id.superseded();
    skipped += id.skipped_for_budget();
  }
  state.counters["sample_thread_of_a_core"] = thread_s / signal_s;
  state.counters["process_of_a_core"] = process_s / signal_s;
  state.counters["budget"] = budget;
  state.counters["fitted_per_s"] = static_cast<double>(fitted) / signal_s;
  state.counters["skipped_for_budget_per_s"] = static_cast<double>(skipped) / signal_s;
  state.counters["dropped_per_s"] = static_cast<double>(dropped) / signal_s;
}
// 60 s with the default budget (two or three of its periods); 5 s without a budget (before it).
BENCHMARK(BM_DaemonLoadRealTime)
    ->Args({60, 0})
    ->Args({5, 1000})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->UseRealTime();

/// The low-pass of the three channels alone (the conditioner's order 4 at 3.3 kHz), per kernel
/// (arg: LowPassFilter::Kernel — 1 scalar, 2 SSE2, 3 AVX; the same results bit for bit), on a
/// second of the simulated 333.3 kHz cut in 1 ms blocks.
void BM_LowPassThree(benchmark::State& state) {
  using Kernel = signal::LowPassFilter::Kernel;
  const auto kernel = static_cast<Kernel>(state.range(0));
  if (kernel == Kernel::kAvx && !signal::cpu_has_avx()) {
    state.SkipWithError("this CPU has no AVX");
    return;
  }
  const double fs = 333300.0;
  const std::size_t block = 333;
  const Recording r = make_recording(fs, 1.0);
  const auto d = signal::ButterworthDesign::lowpass(fs, 3300.0, 4);
  std::array<signal::LowPassFilter, 3> filters = {
      signal::LowPassFilter(d), signal::LowPassFilter(d), signal::LowPassFilter(d)};
  // Filtered again and again in place: a low-pass of the low-passed cut (no subnormals).
  std::vector<double> fx = r.fx, fy = r.fy, fz = r.fz;
  for (auto _ : state) {
    for (std::size_t i = 0; i < fx.size(); i += block) {
      const std::size_t n = std::min(block, fx.size() - i);
      signal::LowPassFilter::process_three(filters, {fx.data() + i, fy.data() + i, fz.data() + i},
                                           n, kernel);
    }
    benchmark::DoNotOptimize(fx.data());
  }
  // items_per_second: samples (of three channels) a second; 1000 / (M/s) = ns a sample.
  state.SetItemsProcessed(static_cast<std::int64_t>(fx.size()) * state.iterations());
}
BENCHMARK(BM_LowPassThree)->Arg(1)->Arg(2)->Arg(3)->Unit(benchmark::kMillisecond);

/// The same low-pass on the measuring grid alone (signal::GridLowPass; args: 0 the fastest
/// kernel, 1 scalar; the stride: 3 what the conditioner runs at 333.3 kHz and 25,000 rpm, 5 and
/// 12 other speeds', unrolled and not), over the same second in the same blocks: the time to
/// compare with BM_LowPassThree's.
void BM_LowPassOnGrid(benchmark::State& state) {
  const auto kernel = static_cast<signal::GridLowPass::Kernel>(state.range(0));
  const double fs = 333300.0;
  const std::size_t block = 333;
  const Recording r = make_recording(fs, 1.0);
  const auto d = signal::ButterworthDesign::lowpass(fs, 3300.0, 4);
  signal::GridLowPass grid(d, static_cast<int>(state.range(1)), {1.0, 1.0, 1.0});
  grid.settle(0, {r.fx[0], r.fy[0], r.fz[0]});
  std::vector<double> x(block), y(block), z(block);
  for (auto _ : state) {
    for (std::size_t i = 0; i < r.fx.size(); i += block) {
      const std::size_t n = std::min(block, r.fx.size() - i);
      grid.process({r.fx.data() + i, r.fy.data() + i, r.fz.data() + i},
                   {x.data(), y.data(), z.data()}, n, kernel);
    }
    benchmark::DoNotOptimize(x.data());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(r.fx.size()) * state.iterations());
}
BENCHMARK(BM_LowPassOnGrid)
    ->Args({0, 3})
    ->Args({1, 3})
    ->Args({0, 5})
    ->Args({1, 5})
    ->Args({0, 12})
    ->Unit(benchmark::kMillisecond);

/// The machine's own latency: a fixed job of about a revolution's work (a chain of 5,000
/// dependent multiply-adds, ~10 µs) run back to back for `seconds`, timed by the wall clock as
/// BM_Pipeline times a revolution. Its worst is what the machine (preemption, the hypervisor's
/// other tenants, interrupts) adds to any job of that size: a pipeline's worst latency beyond it
/// would be the pipeline's own. Counters: job_mean_us, job_p99_us, job_worst_us.
void BM_MachineJitter(benchmark::State& state) {
  const auto seconds = static_cast<double>(state.range(0));
  std::vector<double> jobs_s;
  jobs_s.reserve(1 << 21);
  double x = 1.0;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    auto now = start;
    while (std::chrono::duration<double>(now - start).count() < seconds &&
           jobs_s.size() < jobs_s.capacity()) {
      for (int k = 0; k < 5000; ++k) {
        x = x * 0.999999 + 1e-6;  // stays near 1: no subnormals, no overflow
      }
      benchmark::DoNotOptimize(x);
      const auto end = std::chrono::steady_clock::now();
      jobs_s.push_back(std::chrono::duration<double>(end - now).count());
      now = end;
    }
  }
  count_durations(state, "job", jobs_s);
}
// As long as BM_Pipeline's timed parts at 333.3 kHz in a round (about 10 s of wall clock).
BENCHMARK(BM_MachineJitter)->Arg(10)->Unit(benchmark::kMillisecond)->Iterations(1)->UseRealTime();

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
