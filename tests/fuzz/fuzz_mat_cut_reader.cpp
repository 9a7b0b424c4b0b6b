// libFuzzer: a MATLAB .mat file through shell::MatCutReader: shell/mat_file_check's structure
// check, then libmatio (and HDF5 for v7.3; a v4 file is refused). The reader reads from a path:
// the input goes to a file in memory (memfd) first. Variables are limited to 2^16 elements, so a
// damaged header cannot make the reader allocate what it claims. Invariants: blocks of at most
// 64 samples, in time order, within the utime range; bad samples counted as reported.

#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <stdexcept>
#include <string>

#include "fuzz_support.hpp"
#include "shell/mat_cut_reader.hpp"

using namespace millwatch;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const int fd = memfd_create("fuzz.mat", MFD_CLOEXEC);
  MW_FUZZ_CHECK(fd >= 0);
  std::size_t written = 0;
  while (written < size) {
    const ssize_t n = write(fd, data + written, size - written);
    MW_FUZZ_CHECK(n > 0);
    written += static_cast<std::size_t>(n);
  }
  const std::string path = "/proc/self/fd/" + std::to_string(fd);
  try {
    std::int64_t bad = 0;
    shell::MatCutReader reader(
        path, shell::ColumnMap{}, 50000.0,
        [&](std::int64_t sample, const std::string& problem) {
          MW_FUZZ_CHECK(sample >= 1);
          MW_FUZZ_CHECK(!problem.empty());
          ++bad;
        },
        std::int64_t{1} << 16);
    MW_FUZZ_CHECK(reader.sample_rate_hz() > 0.0);
    bool first = true;
    std::int64_t last_utime_us = 0;
    std::int64_t samples = 0;
    for (auto block = reader.next(64); !block.fx_N.empty(); block = reader.next(64)) {
      MW_FUZZ_CHECK(block.fx_N.size() <= 64);
      MW_FUZZ_CHECK(block.fy_N.size() == block.fx_N.size());
      MW_FUZZ_CHECK(block.fz_N.size() == block.fx_N.size());
      MW_FUZZ_CHECK(block.utime_us >= -monitor::kMaxAbsUtime_us &&
                    block.utime_us <= monitor::kMaxAbsUtime_us);
      MW_FUZZ_CHECK(first || block.utime_us >= last_utime_us);
      first = false;
      last_utime_us = block.utime_us;
      samples += static_cast<std::int64_t>(block.fx_N.size());
    }
    MW_FUZZ_CHECK(reader.bad_samples() == bad);
    MW_FUZZ_CHECK(samples + bad == reader.samples());
  } catch (const std::runtime_error&) {  // not a recording: the run's error, not a crash
  }
  close(fd);
  return 0;
}

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::quiet();
  return 0;
}
