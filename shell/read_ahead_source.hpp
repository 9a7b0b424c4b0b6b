#pragma once
// A recording read on a thread of its own, a few blocks ahead of the pipeline that takes them, so
// that parsing the file overlaps processing it (the replay's wall-clock time is then the longer
// of the two, not their sum).
//
// What the caller sees is what open_recording()'s source gives, in the same order: the same
// blocks; each bad record reported (RecordingOptions::on_bad, in the caller's thread) just before
// the block it preceded, i.e. by the same next() call as without reading ahead; an error the
// reader throws rethrown by the next() that reaches it, after every block before it; bad_records()
// and progress() as they were when the block now returned was read.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>

#include "shell/recording_source.hpp"

namespace millwatch::shell {

/// Where and what: a bad record (RecordingOptions::on_bad).
using OnBadRecord = std::function<void(std::int64_t where, const std::string& problem)>;

/// Reads the source `open` returns ahead in blocks of `max_samples`, which every next() call must
/// then ask for. `open` is called once, here, with the callback its source must report bad
/// records to; they reach `on_bad` as described above.
/// @throws what `open` throws; std::invalid_argument if max_samples is 0
std::unique_ptr<RecordingSource> read_ahead(
    const std::function<std::unique_ptr<RecordingSource>(OnBadRecord)>& open, OnBadRecord on_bad,
    std::size_t max_samples);

/// Opens the recording at `path` as open_recording() does and starts reading it ahead in blocks
/// of `max_samples` (LCM logs: as recorded), which every next() call must then ask for.
/// @throws std::runtime_error as open_recording(); std::invalid_argument if max_samples is 0
std::unique_ptr<RecordingSource> open_recording_read_ahead(const std::filesystem::path& path,
                                                           const RecordingOptions& options,
                                                           std::size_t max_samples);

}  // namespace millwatch::shell
