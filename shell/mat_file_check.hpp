#pragma once
// A MATLAB file's structure checked before libmatio reads it. matio (1.5.23) trusts the sizes a
// file states: a damaged v4 header or v5 tag made it allocate gigabytes (found by
// fuzz_mat_cut_reader), so only files that pass this check reach it:
//
//   v5    the 128-byte header ("MATLAB 5.0 MAT-file", version 0x0100, "IM"/"MI"), then data
//         elements whose sizes fit in the file; each matrix (also inside a compressed element,
//         inflated in a bounded window, its zlib stream ending within the element and its
//         inflated size within the limit): array flags, at most 32 dimensions, a name of at most
//         4 KiB, a numeric, char or logical array of at most max_bytes / 8 elements whose data
//         tag fits in the matrix and claims at most max_bytes, structs and cells to 8 levels with
//         every field and cell a matrix that passes; nothing else (objects, functions, sparse)
//         is read. What lies beyond the first 64 KiB of a matrix is bounded by its size only.
//   v7.3  an HDF5 file behind the 512-byte user block whose text says "MATLAB 7.3 MAT-file":
//         HDF5 reads it (the reader refuses variables above its limit before reading them).
//   v4    (no header of its own) is not read: save with -v7 or -v7.3.
// The header's version field (0x0100, 0x0200) decides which, as in matio: an HDF5 signature
// behind a v5 header does not make the file v7.3 (a fuzzer's find: matio read it as v5).

#include <cstdint>
#include <filesystem>
#include <string>

namespace millwatch::shell {

enum class MatVersion { kV5, kV73 };

struct MatFileCheck {
  MatVersion version = MatVersion::kV5;
  std::string problem;  ///< empty: the file may be read
};

/// Checks the file at `path`; `max_bytes` bounds what any one variable may hold once read.
MatFileCheck check_mat_file(const std::filesystem::path& path, std::int64_t max_bytes);

}  // namespace millwatch::shell
