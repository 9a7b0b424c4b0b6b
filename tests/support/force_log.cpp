#include "tests/support/force_log.hpp"

#include <cmath>
#include <vector>

#include "core/sim/cut_simulator.hpp"
#include "msgs/lcm_convert.hpp"

namespace millwatch::test {

void write_force_event(lcm::LogFile& log, std::int64_t event, const force_block_t& m) {
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(buf.data(), 0, static_cast<int>(buf.size()));
  lcm::LogEvent e{event, m.utime, "MILLWATCH_FORCE_RAW", static_cast<std::int32_t>(buf.size()),
                  buf.data()};
  log.writeEvent(&e);
}

void write_force_log(const std::filesystem::path& path, const sim::Scenario& s,
                     std::size_t block_samples, std::int64_t first_block, std::int64_t end_block) {
  sim::CutSimulator sim(s);
  lcm::LogFile log(path.string(), "w");
  std::vector<double> t(block_samples), fx(block_samples), fy(block_samples), fz(block_samples);
  for (std::int64_t seq = 0; end_block < 0 || seq < end_block; ++seq) {
    const std::size_t n = sim.next_block(t, fx, fy, fz);
    if (n == 0) {
      break;
    }
    if (seq >= first_block) {
      write_force_event(log, seq,
                        messaging::to_message({std::llround(t[0] * 1e6),
                                               seq,
                                               s.sample_rate_hz,
                                               {fx.data(), n},
                                               {fy.data(), n},
                                               {fz.data(), n}}));
    }
  }
}

}  // namespace millwatch::test
