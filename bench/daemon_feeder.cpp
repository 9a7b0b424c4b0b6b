// A DAQ bridge for scripts/daemon_load.sh: publishes raw force_block_t blocks at real time on an
// LCM URL for as long as asked, the same simulated cut as bench/pipeline_benchmark's
// BM_DaemonLoadRealTime (333.3 kHz, 25,250 rpm, noise and quantisation on): 3 s simulated once
// (cached in a file: the simulator runs at a third of real time at this rate), then its last
// ~2.5 s fed again and again — a revolution is 792 samples exactly, so the loop joins without a
// phase step and the daemon's spindle stays locked.
//
//   daemon_feeder --url URL --seconds 40 [--block 333] [--cache FILE] [--channel NAME]

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "bench/benchmark_cut.hpp"
#include "msgs/lcm_convert.hpp"

namespace {

using namespace millwatch;

constexpr double kSampleRate_hz = 333300.0;
constexpr double kSpindle_rpm = 25250.0;
constexpr std::size_t kRevolutionSamples = 792;  // 333,300 · 60 / 25,250

struct Recording {
  std::vector<double> fx_N, fy_N, fz_N;
};

/// BM_DaemonLoadRealTime's cut (bench/benchmark_cut.hpp), 3 s.
Recording simulate() {
  bench::BenchmarkCut c = bench::simulate_benchmark_cut(kSampleRate_hz, 3.0, kSpindle_rpm);
  return {std::move(c.fx), std::move(c.fy), std::move(c.fz)};
}

/// The recording from `cache` (raw doubles: n, then fx, fy, fz), or simulated and written there.
Recording load_or_simulate(const std::string& cache) {
  if (!cache.empty() && std::filesystem::exists(cache)) {
    std::ifstream in(cache, std::ios::binary);
    std::uint64_t n = 0;
    in.read(reinterpret_cast<char*>(&n), sizeof n);
    if (in && n > 0 && n < (1u << 24)) {
      Recording r;
      for (auto* v : {&r.fx_N, &r.fy_N, &r.fz_N}) {
        v->resize(n);
        in.read(reinterpret_cast<char*>(v->data()), static_cast<std::streamsize>(n * 8));
      }
      if (in) {
        return r;
      }
    }
    std::fprintf(stderr, "daemon_feeder: %s is not a cached recording; simulating again\n",
                 cache.c_str());
  }
  Recording r = simulate();
  if (!cache.empty()) {
    std::ofstream out(cache, std::ios::binary);
    const std::uint64_t n = r.fx_N.size();
    out.write(reinterpret_cast<const char*>(&n), sizeof n);
    for (const auto* v : {&r.fx_N, &r.fy_N, &r.fz_N}) {
      out.write(reinterpret_cast<const char*>(v->data()), static_cast<std::streamsize>(n * 8));
    }
  }
  return r;
}

int run(const std::string& url, const std::string& channel, double seconds, std::size_t block,
        const std::string& cache) {
  const Recording r = load_or_simulate(cache);
  lcm::LCM lcm(url);
  if (!lcm.good()) {
    throw std::runtime_error("cannot open LCM at " + url);
  }
  const std::size_t n = r.fx_N.size();
  // The loop starts 0.5 s in, a whole number of revolutions before the end.
  const std::size_t loop_from = n - (n - static_cast<std::size_t>(0.5 * kSampleRate_hz)) /
                                        kRevolutionSamples * kRevolutionSamples;
  std::vector<double> fx(block), fy(block), fz(block);
  const auto total = static_cast<std::size_t>(seconds * kSampleRate_hz) / block * block;
  const auto start = std::chrono::steady_clock::now();
  std::int64_t seq = 0;
  for (std::size_t g = 0; g < total; g += block) {  // g: samples since the start
    for (std::size_t k = 0; k < block; ++k) {
      const std::size_t s = g + k < n ? g + k : loop_from + (g + k - n) % (n - loop_from);
      fx[k] = r.fx_N[s];
      fy[k] = r.fy_N[s];
      fz[k] = r.fz_N[s];
    }
    const double t_s = static_cast<double>(g) / kSampleRate_hz;
    std::this_thread::sleep_until(start + std::chrono::duration<double>(t_s));
    const monitor::SampleBlock b{std::llround(t_s * 1e6), seq++,
                                 kSampleRate_hz,          {fx.data(), block},
                                 {fy.data(), block},      {fz.data(), block}};
    const force_block_t m = messaging::to_message(b);
    lcm.publish(channel, &m);
  }
  std::fprintf(stderr, "daemon_feeder: published %lld blocks of %zu samples on %s\n",
               static_cast<long long>(seq), block, channel.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"daemon_feeder: raw blocks at real time for scripts/daemon_load.sh"};
  std::string url;
  std::string channel = "MILLWATCH_FORCE_RAW";
  std::string cache;
  double seconds = 0.0;
  std::size_t block = 333;
  app.add_option("--url", url, "LCM URL")->required();
  app.add_option("--channel", channel, "Channel of the raw blocks");
  app.add_option("--seconds", seconds, "How long to publish (signal seconds, at real time)")
      ->required()
      ->check(CLI::PositiveNumber);
  app.add_option("--block", block, "Samples per block")->check(CLI::Range(16, 2000));
  app.add_option("--cache", cache, "Cache of the simulated recording (written if absent)");
  CLI11_PARSE(app, argc, argv);
  try {
    return run(url, channel, seconds, block, cache);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "daemon_feeder: %s\n", e.what());
    return 2;
  }
}
