// libFuzzer: a recording in delimited text as users have them — millwatch's CSV, a DynoWare
// export, any delimited text with a column map — read from memory (shell::read_text_layout, then
// CsvCutReader) and its blocks through InputCheck. The input's first line is the column map
// (`--columns` text; one that does not parse means none), the rest the file. Invariants: a map
// that parses writes back as text that parses to the same; the layout's columns lie within what
// a row needs; every block is at most 64 samples, in time order, within the utime range.

#include <cmath>
#include <cstdint>
#include <sstream>
#include <stdexcept>

#include "fuzz_support.hpp"
#include "shell/column_map.hpp"
#include "shell/csv_cut_reader.hpp"
#include "shell/text_layout.hpp"

using namespace millwatch;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string input = fuzz::text(data, size);
  const auto newline = input.find('\n');
  const std::string map_text = input.substr(0, newline);
  shell::ColumnMap map;
  try {
    map = shell::parse_column_map(map_text);
    const std::string written = map.to_string();
    MW_FUZZ_CHECK(shell::parse_column_map(written).to_string() == written);
  } catch (const std::invalid_argument&) {
    map = shell::ColumnMap{};
  }
  std::istringstream in(newline == std::string::npos ? std::string() : input.substr(newline + 1));
  try {
    const shell::TextLayout layout = shell::read_text_layout(in, "fuzz.csv", map);
    for (std::size_t q = 0; q < 4; ++q) {
      MW_FUZZ_CHECK(layout.column[q] < layout.needed_columns);
      MW_FUZZ_CHECK(q == 0 || layout.column[q] >= 0);
    }
    MW_FUZZ_CHECK(layout.header_lines >= 0);
    double rate_hz = layout.sample_rate_hz;
    if (!(rate_hz > 0.0) || !std::isfinite(rate_hz)) {
      rate_hz = 50000.0;  // what the configuration would say
    }
    std::int64_t bad_lines = 0;
    shell::CsvCutReader reader(in, layout, rate_hz,
                               [&](std::int64_t line, const std::string& problem) {
                                 MW_FUZZ_CHECK(line > layout.header_lines);
                                 MW_FUZZ_CHECK(!problem.empty());
                                 ++bad_lines;
                               });
    // The pipeline sees the blocks only at a rate its configuration accepts, [1 kHz, 2 MHz]
    // (monitor_config.cpp): a stranger one is the replay's configuration error.
    const bool accepted = rate_hz >= 1000.0 && rate_hz <= 2e6;
    monitor::InputCheckConfig config;
    config.sample_rate_hz = accepted ? rate_hz : 50000.0;
    config.max_block_samples = 64;
    monitor::InputCheck check(config);
    bool first = true;
    std::int64_t last_utime_us = 0;
    for (auto block = reader.next(64); !block.fx_N.empty(); block = reader.next(64)) {
      MW_FUZZ_CHECK(block.fx_N.size() <= 64);
      MW_FUZZ_CHECK(block.utime_us >= -monitor::kMaxAbsUtime_us &&
                    block.utime_us <= monitor::kMaxAbsUtime_us);
      MW_FUZZ_CHECK(first || block.utime_us >= last_utime_us);
      first = false;
      last_utime_us = block.utime_us;
      if (accepted) {
        fuzz::check_block(check, block);
      }
    }
    MW_FUZZ_CHECK(reader.bad_lines() == bad_lines);
  } catch (const std::runtime_error&) {  // not a recording the map fits: the run's error
  }
  return 0;
}

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::quiet();
  return 0;
}
