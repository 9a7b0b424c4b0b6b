// libFuzzer: one raw-sample datagram as millwatchd receives it. The bytes go over in-process LCM
// (memq://) to the daemon's LcmSource, which checks and decodes them into the block queue's slot
// (the values lcm-gen's decode gives, to the bit); a queued block then goes through InputCheck.
// Also the check itself: a message it passes decodes to exactly its declared count; and the same
// bytes as a udpm datagram (msgs/lcm_datagram.hpp, millwatchd's batched receive): what it reads
// lies within them.

#include <bit>
#include <cstdint>
#include <lcm/lcm-cpp.hpp>
#include <memory>

#include "daemon/lcm_source.hpp"
#include "fuzz_support.hpp"
#include "msgs/force_block_check.hpp"
#include "msgs/lcm_datagram.hpp"

using namespace millwatch;

namespace {

constexpr std::int64_t kMax = 512;

struct Daemon {
  lcm::LCM lcm{"memq://"};
  std::unique_ptr<daemon::BlockQueue> queue = std::make_unique<daemon::BlockQueue>();
  daemon::SourceCounters counters;
  daemon::LcmSource source{lcm, "RAW", kMax, *queue, counters};
  std::unique_ptr<daemon::BlockSlot> slot = std::make_unique<daemon::BlockSlot>();
  monitor::InputCheck check{[] {
    monitor::InputCheckConfig c;
    c.sample_rate_hz = 50000.0;
    c.max_block_samples = daemon::BlockSlot::kMaxSamples;
    return c;
  }()};
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const messaging::LcmDatagram datagram = messaging::parse_lcm_datagram({data, size});
  if (datagram.kind != messaging::LcmDatagram::Kind::kNotLcm) {
    MW_FUZZ_CHECK(datagram.payload.data() >= data &&
                  datagram.payload.data() + datagram.payload.size() <= data + size);
    MW_FUZZ_CHECK(datagram.channel.size() <= messaging::kLcmMaxChannelBytes);
  }
  const messaging::ForceBlockCheck c = messaging::check_force_block(data, size, kMax);
  force_block_t m;
  const messaging::ForceBlockCheck decoded = messaging::decode_force_block(data, size, kMax, m);
  MW_FUZZ_CHECK(c.problem == decoded.problem);
  MW_FUZZ_CHECK(!c.describe().empty());
  if (c.ok()) {
    MW_FUZZ_CHECK(m.num_samples == c.num_samples);
    MW_FUZZ_CHECK(static_cast<std::int64_t>(m.fx_N.size()) == c.num_samples);
    MW_FUZZ_CHECK(m.fy_N.size() == m.fx_N.size() && m.fz_N.size() == m.fx_N.size());
  }

  static Daemon daemon;
  const std::int64_t before = daemon.counters.messages.load();
  daemon.lcm.publish("RAW", data, static_cast<unsigned>(size));
  MW_FUZZ_CHECK(daemon.lcm.handleTimeout(1000) == 1);
  MW_FUZZ_CHECK(daemon.counters.messages.load() == before + 1);
  while (daemon.queue->try_pop(*daemon.slot)) {
    MW_FUZZ_CHECK(c.ok());
    MW_FUZZ_CHECK(static_cast<std::int64_t>(daemon.slot->count) == c.num_samples);
    // The source decodes into the slot itself: the values lcm-gen's decode gives, to the bit.
    MW_FUZZ_CHECK(daemon.slot->utime_us == m.utime && daemon.slot->seq == m.seq);
    const auto same = [](double a, double b) {
      return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
    };
    MW_FUZZ_CHECK(same(daemon.slot->sample_rate_hz, m.sample_rate_hz));
    for (std::size_t i = 0; i < daemon.slot->count; ++i) {
      MW_FUZZ_CHECK(same(daemon.slot->fx[i], m.fx_N[i]) && same(daemon.slot->fy[i], m.fy_N[i]) &&
                    same(daemon.slot->fz[i], m.fz_N[i]));
    }
    fuzz::check_block(daemon.check, daemon.slot->view());
  }
  return 0;
}

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::quiet();
  return 0;
}
