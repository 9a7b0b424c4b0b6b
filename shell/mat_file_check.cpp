#include "shell/mat_file_check.hpp"

#include <zlib.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <fstream>
#include <vector>

namespace millwatch::shell {
namespace {

constexpr std::size_t kWindow = 64 * 1024;  // bytes of a matrix element looked at
constexpr int kMaxDepth = 8;
constexpr std::uint32_t kMiInt8 = 1, kMiInt32 = 5, kMiUint32 = 6, kMiMatrix = 14,
                        kMiCompressed = 15;

/// A bounded view of an element's bytes: `claimed` bytes exist, the first `data.size()` are here.
class Element {
 public:
  Element(const std::uint8_t* data, std::size_t available, std::uint64_t claimed, bool swap)
      : data_(data), available_(available), claimed_(claimed), swap_(swap) {}

  struct Sub {
    std::uint32_t type = 0;
    std::uint64_t bytes = 0;
    std::size_t at = 0;    // first data byte
    bool visible = false;  // the data bytes are within the window
  };

  /// The subelement at `pos`; false with `problem` set if its tag breaks the bounds, false with
  /// no problem if its tag lies beyond the window (nothing more can be checked).
  bool sub(std::size_t& pos, Sub& s, std::string& problem) const {
    if (pos + 8 > claimed_) {
      problem = "a matrix ends inside a tag";
      return false;
    }
    if (pos + 8 > available_) {
      return false;
    }
    const std::uint32_t first = u32(pos);
    if ((first >> 16) != 0) {  // small data element: size and type in one word, data in the next
      s.type = first & 0xFFFF;
      s.bytes = first >> 16;
      if (s.bytes > 4) {
        problem = "a small data element of more than 4 bytes";
        return false;
      }
      s.at = pos + 4;
      pos += 8;
    } else {
      s.type = first;
      s.bytes = u32(pos + 4);
      s.at = pos + 8;
      if (s.bytes > claimed_ - s.at) {
        problem = "a subelement of " + std::to_string(s.bytes) + " bytes in a matrix of " +
                  std::to_string(claimed_) + " bytes";
        return false;
      }
      pos = s.at + static_cast<std::size_t>((s.bytes + 7) / 8 * 8);
    }
    s.visible = s.at + s.bytes <= available_;
    return true;
  }
  [[nodiscard]] std::uint32_t u32(std::size_t at) const {
    std::uint32_t v = 0;
    std::memcpy(&v, data_ + at, 4);
    return swap_ ? __builtin_bswap32(v) : v;
  }
  [[nodiscard]] std::int32_t i32(std::size_t at) const {
    return static_cast<std::int32_t>(u32(at));
  }
  [[nodiscard]] std::uint64_t claimed() const { return claimed_; }
  [[nodiscard]] bool swapped() const { return swap_; }
  [[nodiscard]] const std::uint8_t* data() const { return data_; }
  [[nodiscard]] std::size_t available() const { return available_; }

 private:
  const std::uint8_t* data_;
  std::size_t available_;
  std::uint64_t claimed_;
  bool swap_;
};

/// Checks a miMATRIX element's contents; empty if sound (or unseen beyond the window).
std::string check_matrix(const Element& e, std::uint64_t max_bytes, int depth) {
  if (depth > kMaxDepth) {
    return "structs or cells nested deeper than " + std::to_string(kMaxDepth) + " levels";
  }
  if (e.claimed() == 0) {
    // An empty cell or field; a variable has at least flags, dimensions and a name, and matio
    // reads them from the bytes after an empty top-level element regardless (a fuzzer's find).
    return depth == 0 ? "a variable of 0 bytes (no array flags, dimensions or name)" : "";
  }
  std::size_t pos = 0;
  Element::Sub flags, dims, name;
  std::string problem;
  if (!e.sub(pos, flags, problem)) {
    return problem;
  }
  if (flags.type != kMiUint32 || flags.bytes != 8 || !flags.visible) {
    return flags.visible || !problem.empty() ? "a matrix without its array flags" : "";
  }
  const std::uint32_t klass = e.u32(flags.at) & 0xFF;
  if (!e.sub(pos, dims, problem)) {
    return problem;
  }
  if (dims.type != kMiInt32 || dims.bytes % 4 != 0 || dims.bytes < 8 || dims.bytes > 4 * 32) {
    return "a matrix whose dimensions are not 2 to 32 int32";
  }
  if (!dims.visible) {
    return {};
  }
  std::uint64_t elements = 1;
  for (std::size_t k = 0; k < dims.bytes / 4; ++k) {
    const std::int32_t d = e.i32(dims.at + 4 * k);
    if (d < 0) {
      return "a negative dimension";
    }
    elements = std::min<std::uint64_t>(elements * static_cast<std::uint64_t>(d), max_bytes + 1);
  }
  if (!e.sub(pos, name, problem)) {
    return problem;
  }
  if (name.type != kMiInt8 || name.bytes > 4096) {
    return "a matrix name that is not int8 text of at most 4096 bytes";
  }
  // mxCELL 1, mxSTRUCT 2, mxOBJECT 3, mxCHAR 4, mxSPARSE 5, numeric 6-15.
  if (klass >= 4 && klass <= 15 && klass != 5) {
    if (elements * 8 > max_bytes) {  // read as up to 8 bytes an element
      return "an array of " + std::to_string(elements) + " elements, more than the " +
             std::to_string(max_bytes / 8) + " allowed";
    }
    // The data's own tag: matio allocates what a char array's tag says (found by
    // fuzz_mat_cut_reader: a tag of "MATL" asked for 1.28 GB).
    Element::Sub data;
    if (pos >= e.claimed()) {
      return {};  // no data at all (an empty array)
    }
    if (!e.sub(pos, data, problem)) {
      return problem;  // empty: beyond the window
    }
    if (data.bytes > max_bytes) {
      return "array data of " + std::to_string(data.bytes) + " bytes, more than the " +
             std::to_string(max_bytes) + " allowed";
    }
    return {};
  }
  if (klass == 1 || klass == 2) {
    std::uint64_t fields = 1;
    if (klass == 2) {
      Element::Sub length, names;
      if (!e.sub(pos, length, problem)) {
        return problem;
      }
      if (length.type != kMiInt32 || length.bytes != 4 || length.at + 4 > e.available()) {
        return length.at + 4 > e.available() ? "" : "a struct without its field name length";
      }
      const std::int32_t l = e.i32(length.at);
      if (l <= 0 || l > 4096) {
        return "a struct field name length of " + std::to_string(l);
      }
      if (!e.sub(pos, names, problem)) {
        return problem;
      }
      if (names.type != kMiInt8 || names.bytes % static_cast<std::uint64_t>(l) != 0) {
        return "a struct's field names that are not int8 text";
      }
      fields = names.bytes / static_cast<std::uint64_t>(l);
    }
    if (elements * fields > 1000000) {
      return "a struct or cell of more than 10^6 parts";
    }
    for (std::uint64_t k = 0; k < elements * fields; ++k) {
      Element::Sub part;
      if (!e.sub(pos, part, problem)) {
        return problem;
      }
      if (part.type != kMiMatrix) {
        return "a struct field or cell that is not a matrix";
      }
      const std::size_t seen = part.at >= e.available()
                                   ? 0
                                   : static_cast<std::size_t>(std::min<std::uint64_t>(
                                         e.available() - part.at, part.bytes));
      if (seen == 0 && part.bytes > 0) {
        return {};  // beyond the window
      }
      if (const std::string p = check_matrix(
              Element(e.data() + part.at, seen, part.bytes, e.swapped()), max_bytes, depth + 1);
          !p.empty()) {
        return p;
      }
    }
    return {};
  }
  return klass == 5   ? "a sparse matrix (not read)"
         : klass == 3 ? "an object (not read)"
                      : "a matrix of class " + std::to_string(klass);
}

}  // namespace

MatFileCheck check_mat_file(const std::filesystem::path& path, std::int64_t max_bytes_signed) {
  MatFileCheck out;
  const auto max_bytes = static_cast<std::uint64_t>(std::max<std::int64_t>(max_bytes_signed, 0));
  std::ifstream in(path, std::ios::binary);
  std::array<char, 520> head{};
  in.read(head.data(), head.size());
  const auto got = static_cast<std::size_t>(in.gcount());
  const std::string_view h(head.data(), got);
  // matio picks the format from the header's version field (0x0100 v5, 0x0200 v7.3), not
  // from the HDF5 signature: a v5 header over an HDF5 block is read as v5 and must be checked
  // as v5 (found by fuzz_mat_cut_reader: such a file made matio allocate 1.3 GB).
  const bool has_endian = got >= 128 && (h.substr(126, 2) == "IM" || h.substr(126, 2) == "MI");
  const bool swap = has_endian && h.substr(126, 2) == "MI";
  std::uint16_t version = 0;
  if (has_endian) {
    std::memcpy(&version, head.data() + 124, 2);
    version = swap ? __builtin_bswap16(version) : version;
  }
  if (has_endian && version == 0x0200) {
    out.version = MatVersion::kV73;
    if (got < 520 || h.substr(512, 8) != std::string_view("\x89HDF\r\n\x1A\n", 8)) {
      out.problem = "a v7.3 MAT-file header without the HDF5 file behind it";
    } else if (h.substr(0, 19) != "MATLAB 7.3 MAT-file") {
      out.problem = "an HDF5 file that is not a MATLAB 7.3 MAT-file";
    }
    return out;
  }
  if (!has_endian || h.substr(0, 6) != "MATLAB" || version != 0x0100) {
    out.problem = h.substr(0, 6) == "MATLAB" ? "a damaged MAT-file header"
                                             : "not a MAT-file of version 5 or 7.3 (a v4 file: "
                                               "save it with -v7 or -v7.3)";
    return out;
  }
  in.clear();
  in.seekg(0, std::ios::end);
  const auto size = static_cast<std::uint64_t>(std::max<std::streamoff>(in.tellg(), 0));
  std::uint64_t offset = 128;
  std::vector<std::uint8_t> window;
  std::vector<std::uint8_t> compressed;
  auto u32 = [swap](const std::uint8_t* p) {
    std::uint32_t v = 0;
    std::memcpy(&v, p, 4);
    return swap ? __builtin_bswap32(v) : v;
  };
  while (offset + 8 <= size) {
    std::array<std::uint8_t, 8> tag{};
    in.clear();
    in.seekg(static_cast<std::streamoff>(offset));
    in.read(reinterpret_cast<char*>(tag.data()), 8);
    std::uint32_t type = u32(tag.data());
    std::uint64_t bytes = u32(tag.data() + 4);
    if ((type >> 16) != 0) {
      offset += 8;  // a small element at the top level: nothing to read
      continue;
    }
    if (bytes > size - offset - 8) {
      out.problem = "the element at byte " + std::to_string(offset) + " claims " +
                    std::to_string(bytes) + " bytes; " + std::to_string(size - offset - 8) +
                    " are left";
      return out;
    }
    const std::string where = "the element at byte " + std::to_string(offset) + ": ";
    if (type == kMiMatrix && bytes % 8 != 0) {
      // A matrix is padded to 8 bytes; matio takes the next element from the unpadded end, the
      // check from the padded one: they would read different elements (found by
      // fuzz_mat_cut_reader: a 196-byte matrix hid a 1.3 GB dimension tag from the check).
      out.problem =
          where + "a matrix of " + std::to_string(bytes) + " bytes, not padded to a multiple of 8";
      return out;
    }
    if (type == kMiMatrix) {
      window.resize(static_cast<std::size_t>(std::min<std::uint64_t>(bytes, kWindow)));
      in.read(reinterpret_cast<char*>(window.data()), static_cast<std::streamsize>(window.size()));
      const std::string p =
          check_matrix(Element(window.data(), window.size(), bytes, swap), max_bytes, 0);
      if (!p.empty()) {
        out.problem = where + p;
        return out;
      }
    } else if (type == kMiCompressed) {
      // Read and inflated in chunks: the first kWindow bytes kept, the rest only counted.
      z_stream z{};
      if (inflateInit(&z) != Z_OK) {
        out.problem = "zlib cannot start";
        return out;
      }
      window.assign(kWindow, 0);
      std::vector<std::uint8_t> sink(kWindow);
      compressed.resize(kWindow);
      std::uint64_t left = bytes;
      std::uint64_t total = 0;
      int rc = Z_OK;
      while (rc == Z_OK) {
        if (z.avail_in == 0 && left > 0) {
          const auto n = static_cast<std::size_t>(std::min<std::uint64_t>(left, kWindow));
          in.read(reinterpret_cast<char*>(compressed.data()), static_cast<std::streamsize>(n));
          z.next_in = compressed.data();
          z.avail_in = static_cast<uInt>(n);
          left -= n;
        }
        std::uint8_t* to = total < kWindow ? window.data() + total : sink.data();
        const std::size_t room =
            total < kWindow ? kWindow - static_cast<std::size_t>(total) : kWindow;
        z.next_out = to;
        z.avail_out = static_cast<uInt>(room);
        rc = inflate(&z, Z_NO_FLUSH);
        total += room - z.avail_out;
        if (total > max_bytes + kWindow) {
          inflateEnd(&z);
          out.problem =
              where + "inflates to more than " + std::to_string(max_bytes + kWindow) + " bytes";
          return out;
        }
        if (rc == Z_BUF_ERROR && z.avail_in == 0 && left == 0) {
          break;  // the element ends before its stream does
        }
        if (rc == Z_BUF_ERROR) {
          rc = Z_OK;  // more input to come
        }
      }
      inflateEnd(&z);
      if (rc == Z_BUF_ERROR) {
        // matio does not stop at the element's end: it inflates on into whatever follows, and
        // trusts the sizes it finds there (found by fuzz_mat_cut_reader: a 7-byte element whose
        // stream went on into the next bytes named a variable of 1.3 GB).
        out.problem = where + "a compressed element of " + std::to_string(bytes) +
                      " bytes whose stream does not end within it";
        return out;
      }
      if (rc != Z_STREAM_END) {
        out.problem =
            where + "does not inflate (zlib: " + (z.msg != nullptr ? z.msg : "error") + ")";
        return out;
      }
      const std::size_t seen = static_cast<std::size_t>(std::min<std::uint64_t>(total, kWindow));
      if (seen < 8 || u32(window.data()) != kMiMatrix || u32(window.data() + 4) > total - 8) {
        out.problem = where + "a compressed element that is not a whole matrix";
        return out;
      }
      const std::string p = check_matrix(
          Element(window.data() + 8, seen - 8, u32(window.data() + 4), swap), max_bytes, 0);
      if (!p.empty()) {
        out.problem = where + p;
        return out;
      }
    }
    // Compressed elements are not padded to 8 bytes; the others are.
    offset += 8 + (type == kMiCompressed ? bytes : (bytes + 7) / 8 * 8);
  }
  return out;
}

}  // namespace millwatch::shell
