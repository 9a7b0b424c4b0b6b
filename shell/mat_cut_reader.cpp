#include "shell/mat_cut_reader.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <utility>

#include "core/monitor/input_check.hpp"
#include "shell/isolated_call.hpp"
#include "shell/mat_file_check.hpp"
#include "shell/matio_library.hpp"

namespace millwatch::shell {
namespace {

namespace fs = std::filesystem;

/// matio reports through a logger that prints to stderr; its messages are kept for ours.
thread_local std::string g_matio_message;
extern "C" void matio_log(int /*level*/, char* message) {
  if (message != nullptr) {
    g_matio_message = message;
  }
}
void quiet_matio() {
  static std::once_flag once;
  std::call_once(once, [] {
    // HDF5 1.10.8 cannot close a file whose H5Fopen failed half-way (a damaged v7.3 file): its
    // cleanup at exit then prints "HDF5: infinite loop closing library" and a line of
    // abbreviations after our error. Only read here, so nothing needs HDF5's cleanup. It must
    // come before HDF5's first use (Mat_LogInitFunc is one: it turns HDF5's error printing off);
    // in a process that wrote a v7.3 file before, it comes too late and changes nothing.
    const MatioLibrary& m = matio_library();
    if (m.hdf5_dont_atexit != nullptr) {
      m.hdf5_dont_atexit();
    }
    m.log_init("millwatch", matio_log);
  });
}

struct MatFile {
  mat_t* mat = nullptr;
  ~MatFile() {
    if (mat != nullptr) {
      matio_library().close(mat);
    }
  }
};
struct VarDeleter {
  void operator()(matvar_t* v) const { matio_library().free(v); }
};
using Var = std::unique_ptr<matvar_t, VarDeleter>;

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

const char* class_name(matio_classes c) {
  switch (c) {
    case MAT_C_DOUBLE:
      return "double";
    case MAT_C_SINGLE:
      return "single";
    case MAT_C_INT8:
      return "int8";
    case MAT_C_UINT8:
      return "uint8";
    case MAT_C_INT16:
      return "int16";
    case MAT_C_UINT16:
      return "uint16";
    case MAT_C_INT32:
      return "int32";
    case MAT_C_UINT32:
      return "uint32";
    case MAT_C_INT64:
      return "int64";
    case MAT_C_UINT64:
      return "uint64";
    case MAT_C_STRUCT:
      return "struct";
    case MAT_C_CELL:
      return "cell";
    case MAT_C_CHAR:
      return "char";
    case MAT_C_SPARSE:
      return "sparse";
    default:
      return "other";
  }
}

std::size_t element_size(matio_classes c) {
  switch (c) {
    case MAT_C_DOUBLE:
    case MAT_C_INT64:
    case MAT_C_UINT64:
      return 8;
    case MAT_C_SINGLE:
    case MAT_C_INT32:
    case MAT_C_UINT32:
      return 4;
    case MAT_C_INT16:
    case MAT_C_UINT16:
      return 2;
    case MAT_C_INT8:
    case MAT_C_UINT8:
      return 1;
    default:
      return 0;
  }
}

/// Elements of a variable (rank ≥ 1), or -1 if the product overflows or a dimension is absent.
std::int64_t elements(const matvar_t* v) {
  if (v == nullptr || v->dims == nullptr || v->rank < 1) {
    return -1;
  }
  std::int64_t n = 1;
  for (int i = 0; i < v->rank; ++i) {
    const std::size_t d = v->dims[i];
    if (d > static_cast<std::size_t>(std::numeric_limits<std::int64_t>::max()) ||
        (d > 0 && n > std::numeric_limits<std::int64_t>::max() / static_cast<std::int64_t>(d))) {
      return -1;
    }
    n *= static_cast<std::int64_t>(d);
  }
  return n;
}

/// "5000×3 double".
std::string shape(const matvar_t* v) {
  std::string s;
  for (int i = 0; i < v->rank && v->dims != nullptr && i < 8; ++i) {
    s += (i > 0 ? "\xC3\x97" : "") + std::to_string(v->dims[i]);
  }
  return s + " " + class_name(v->class_type);
}

/// "F 5000×3 double".
std::string describe(const matvar_t* v) {
  return std::string(v->name != nullptr ? v->name : "?") + " " + shape(v);
}

/// What a ColumnSpec names in a .mat: variable, optional struct field, optional row/column.
struct Selector {
  std::string variable;
  std::string field;
  char slice = 0;  // 0 the whole vector, 'c' column k, 'r' row k
  std::size_t k = 0;
  double scale = 1.0;
  static Selector whole(const std::string& v) {
    Selector s;
    s.variable = v;
    return s;
  }
  [[nodiscard]] std::string text() const {
    std::string s = variable + (field.empty() ? "" : "." + field);
    if (slice == 'c') {
      s += "(:," + std::to_string(k + 1) + ")";
    } else if (slice == 'r') {
      s += "(" + std::to_string(k + 1) + ",:)";
    }
    return s;
  }
};

Selector parse_selector(const ColumnSpec& spec, const std::string& key, const std::string& name) {
  Selector s;
  s.scale = spec.scale;
  if (spec.index > 0) {
    throw std::runtime_error(name + ": columns: " + key + "=" + std::to_string(spec.index) +
                             ": a .mat file's columns are variables, e.g. " + key + "=F(:,1) or " +
                             key + "=Fx");
  }
  std::string text = spec.source;
  if (const auto open = text.find('('); open != std::string::npos) {
    const std::string inside = text.substr(open + 1, text.size() - open - 2);
    const bool closed = text.back() == ')';
    text = text.substr(0, open);
    const auto comma = inside.find(',');
    int index = 0;
    auto number = [&](const std::string& t) {
      const auto r = std::from_chars(t.data(), t.data() + t.size(), index);
      return r.ec == std::errc() && r.ptr == t.data() + t.size() && index >= 1;
    };
    if (!closed || comma == std::string::npos) {
      index = 0;
    } else if (inside.substr(0, comma) == ":" && number(inside.substr(comma + 1))) {
      s.slice = 'c';
    } else if (inside.substr(comma + 1) == ":" && number(inside.substr(0, comma))) {
      s.slice = 'r';
    }
    if (s.slice == 0) {
      throw std::runtime_error(name + ": columns: " + key + "=" + spec.source +
                               ": expected NAME(:,k) or NAME(k,:) with k ≥ 1");
    }
    s.k = static_cast<std::size_t>(index - 1);
  }
  if (const auto dot = text.find('.'); dot != std::string::npos) {
    s.field = text.substr(dot + 1);
    text = text.substr(0, dot);
  }
  s.variable = text;
  if (s.variable.empty()) {
    throw std::runtime_error(name + ": columns: " + key + ": no variable named");
  }
  return s;
}

template <class T>
void append_as_double(const void* data, std::size_t first, std::size_t count, std::size_t stride,
                      std::vector<double>& out) {
  const T* p = static_cast<const T*>(data);
  out.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    out.push_back(static_cast<double>(p[first + i * stride]));
  }
}

class Reader {
 public:
  /// Opens a file check_mat_file() passed, after quiet_matio().
  Reader(const fs::path& path, std::int64_t max_elements)
      : name_(path.string()), max_elements_(max_elements) {
    g_matio_message.clear();
    file_.mat = matio_library().open(path.c_str(), MAT_ACC_RDONLY);
    if (file_.mat == nullptr) {
      throw std::runtime_error(name_ + ": cannot read as a MATLAB .mat file" +
                               (g_matio_message.empty() ? "" : " (" + g_matio_message + ")"));
    }
    switch (matio_library().version(file_.mat)) {
      case MAT_FT_MAT73:
        version_ = "v7.3";
        break;
      case MAT_FT_MAT5:
        version_ = "v5";
        break;
      default:
        version_ = "?";
    }
    // The variables' names, shapes and classes (no data read yet).
    for (int n = 0; n < 10000; ++n) {
      Var v(matio_library().read_next_info(file_.mat));
      if (!v) {
        break;
      }
      if (v->name != nullptr) {
        infos_.push_back(describe(v.get()));
        names_.emplace_back(v->name);
        ranks_.push_back(v->rank);
        dims_.push_back(
            {v->rank >= 1 && v->dims ? v->dims[0] : 0, v->rank >= 2 && v->dims ? v->dims[1] : 0});
        elements_.push_back(elements(v.get()));
        classes_.push_back(v->class_type);
      }
    }
    matio_library().rewind(file_.mat);
    if (names_.empty()) {
      // matio opens a v7.3 file whose HDF5 structure cannot be read (H5Fopen fails) as one
      // without variables (found by fuzz_mat_cut_reader).
      throw std::runtime_error(name_ + ": no variable can be read from this " + version_ +
                               " MAT-file (empty or damaged" +
                               (version_ == "v7.3" ? ": HDF5 cannot open it)" : ")"));
    }
  }

  [[nodiscard]] const std::string& version() const { return version_; }

  /// The variable's name as the file spells it, found case-insensitively if need be.
  [[nodiscard]] std::optional<std::size_t> find(const std::string& variable) const {
    for (std::size_t i = 0; i < names_.size(); ++i) {
      if (names_[i] == variable) {
        return i;
      }
    }
    for (std::size_t i = 0; i < names_.size(); ++i) {
      if (lower(names_[i]) == lower(variable)) {
        return i;
      }
    }
    return std::nullopt;
  }
  [[nodiscard]] std::optional<std::size_t> find_any(std::initializer_list<const char*> names,
                                                    bool matrix3 = false) const {
    for (const char* n : names) {
      if (const auto i = find(n)) {
        const bool has3 = dims_[*i][0] == 3 || dims_[*i][1] == 3;
        if (!matrix3 || (ranks_[*i] == 2 && has3 && std::min(dims_[*i][0], dims_[*i][1]) > 0)) {
          return i;
        }
      }
    }
    return std::nullopt;
  }
  [[nodiscard]] const std::string& name_of(std::size_t i) const { return names_[i]; }
  [[nodiscard]] std::array<std::size_t, 2> dims_of(std::size_t i) const { return dims_[i]; }

  [[nodiscard]] std::string listing() const {
    std::string s;
    for (const auto& i : infos_) {
      s += (s.empty() ? "" : ", ") + i;
      if (s.size() > 300) {
        return s + ", ...";
      }
    }
    return s.empty() ? "none" : s;
  }

  /// The selected numbers as doubles (times the selector's scale).
  std::vector<double> read(const Selector& s, const std::string& key) {
    const auto i = find(s.variable);
    if (!i) {
      throw std::runtime_error(name_ + ": no variable \"" + s.variable + "\" for " + key +
                               " (variables: " + listing() + ")");
    }
    const std::string& variable = names_[*i];
    if (elements_[*i] < 0 || elements_[*i] > max_elements_) {
      throw std::runtime_error(name_ + ": variable " + infos_[*i] + " for " + key +
                               " is too large (at most " + std::to_string(max_elements_) +
                               " elements)");
    }
    g_matio_message.clear();
    Var whole(matio_library().read(file_.mat, variable.c_str()));
    if (!whole) {
      throw std::runtime_error(name_ + ": variable " + variable + " cannot be read" +
                               (g_matio_message.empty() ? "" : " (" + g_matio_message + ")"));
    }
    const matvar_t* v = whole.get();
    if (!s.field.empty()) {
      if (v->class_type != MAT_C_STRUCT) {
        throw std::runtime_error(name_ + ": " + key + ": " + variable + " is a " +
                                 class_name(v->class_type) + ", not a struct with a field " +
                                 s.field);
      }
      if (elements(v) != 1) {
        throw std::runtime_error(name_ + ": " + key + ": " + variable +
                                 " is a struct array; name a field of a 1×1 struct");
      }
      v = matio_library().struct_field(whole.get(), s.field.c_str(), 0);
      if (v == nullptr) {
        throw std::runtime_error(name_ + ": " + key + ": struct " + variable + " has no field " +
                                 s.field);
      }
    }
    const std::string what = s.text();
    const std::string base = s.variable + (s.field.empty() ? "" : "." + s.field);  // no slice
    const std::size_t size = element_size(v->class_type);
    const std::int64_t n = elements(v);
    if (size == 0 || v->isComplex != 0) {
      throw std::runtime_error(
          name_ + ": " + key + ": " + what + " is " +
          (v->isComplex != 0 ? std::string("complex") : class_name(v->class_type)) +
          "; expected real numbers");
    }
    if (n < 0 || n > max_elements_ || v->rank != 2 || v->dims == nullptr || v->data == nullptr ||
        v->data_size != static_cast<int>(size) || v->nbytes < static_cast<std::size_t>(n) * size) {
      throw std::runtime_error(name_ + ": " + key + ": " + what +
                               " is not a readable 2-D numeric array (" + describe(v) + ")");
    }
    const std::size_t rows = v->dims[0];
    const std::size_t cols = v->dims[1];
    std::size_t first = 0;
    std::size_t count = static_cast<std::size_t>(n);
    std::size_t stride = 1;
    if (s.slice == 'c') {
      if (s.k >= cols) {
        throw std::runtime_error(name_ + ": " + key + ": " + what + ": " + base + " (" + shape(v) +
                                 ") has " + std::to_string(cols) + " columns");
      }
      first = s.k * rows;
      count = rows;
    } else if (s.slice == 'r') {
      if (s.k >= rows) {
        throw std::runtime_error(name_ + ": " + key + ": " + what + ": " + base + " (" + shape(v) +
                                 ") has " + std::to_string(rows) + " rows");
      }
      first = s.k;
      count = cols;
      stride = rows;
    } else if (rows != 1 && cols != 1) {
      throw std::runtime_error(name_ + ": " + key + ": " + what + " (" + shape(v) +
                               ") is a matrix; name a column (" + what + "(:,1)) or a row");
    }
    std::vector<double> out;
    switch (v->class_type) {
      case MAT_C_DOUBLE:
        append_as_double<double>(v->data, first, count, stride, out);
        break;
      case MAT_C_SINGLE:
        append_as_double<float>(v->data, first, count, stride, out);
        break;
      case MAT_C_INT8:
        append_as_double<std::int8_t>(v->data, first, count, stride, out);
        break;
      case MAT_C_UINT8:
        append_as_double<std::uint8_t>(v->data, first, count, stride, out);
        break;
      case MAT_C_INT16:
        append_as_double<std::int16_t>(v->data, first, count, stride, out);
        break;
      case MAT_C_UINT16:
        append_as_double<std::uint16_t>(v->data, first, count, stride, out);
        break;
      case MAT_C_INT32:
        append_as_double<std::int32_t>(v->data, first, count, stride, out);
        break;
      case MAT_C_UINT32:
        append_as_double<std::uint32_t>(v->data, first, count, stride, out);
        break;
      case MAT_C_INT64:
        append_as_double<std::int64_t>(v->data, first, count, stride, out);
        break;
      default:
        append_as_double<std::uint64_t>(v->data, first, count, stride, out);
        break;
    }
    if (s.scale != 1.0) {
      for (double& x : out) {
        x *= s.scale;
      }
    }
    return out;
  }

 private:
  std::string name_;
  std::int64_t max_elements_;
  MatFile file_;
  std::string version_;
  std::vector<std::string> infos_, names_;
  std::vector<int> ranks_;
  std::vector<std::array<std::size_t, 2>> dims_;
  std::vector<std::int64_t> elements_;
  std::vector<matio_classes> classes_;
};

std::string number(double v) {
  std::array<char, 32> text{};
  const auto r = std::to_chars(text.data(), text.data() + text.size(), v);
  return {text.data(), r.ptr};
}

/// What a file gives the reader: forces, time, rate and which variables they came from.
struct Contents {
  std::array<std::vector<double>, 3> f;
  std::vector<double> t;  // empty: no time vector
  double rate_hz = 0.0;
  bool rate_stated = false;
  std::string version;
  std::string variables;
};

void put_size(AnswerWriter& out, std::size_t n) {
  const std::uint64_t v = n;
  out.write(&v, sizeof v);
}

/// Contents as the reading process's answer, written straight from its vectors: the answer can
/// be gigabytes, which a copy would double.
void write_contents(AnswerWriter& out, const Contents& c) {
  for (const std::vector<double>* v : {&c.f[0], &c.f[1], &c.f[2], &c.t}) {
    put_size(out, v->size());
    out.write(v->data(), v->size() * sizeof(double));
  }
  out.write(&c.rate_hz, sizeof c.rate_hz);
  put_size(out, c.rate_stated ? 1 : 0);
  for (const std::string* text : {&c.version, &c.variables}) {
    put_size(out, text->size());
    out.write(text->data(), text->size());
  }
}

/// A count of items of `item_bytes` each, at most `most` and no more than the answer has left
/// (checked before anyone allocates for them).
std::size_t get_size(AnswerReader& in, std::size_t most, std::size_t item_bytes) {
  std::uint64_t v = 0;
  in.read(&v, sizeof v);
  const std::size_t limit = std::min(most, in.left() / item_bytes);
  if (v > limit) {
    throw std::runtime_error("the reading process's answer states " + std::to_string(v) +
                             " items, more than the " + std::to_string(limit) + " it may");
  }
  return static_cast<std::size_t>(v);
}

/// The most a text of the answer may hold (its names and selectors: a few hundred characters).
constexpr std::size_t kMaxAnswerTextBytes = std::size_t{1} << 20;

/// Reads write_contents()'s answer straight into the vectors; throws if it is not what it wrote.
Contents read_answer(AnswerReader& in, std::size_t max_elements) {
  Contents c;
  for (std::vector<double>* v : {&c.f[0], &c.f[1], &c.f[2], &c.t}) {
    v->resize(get_size(in, max_elements, sizeof(double)));
    in.read(v->data(), v->size() * sizeof(double));
  }
  in.read(&c.rate_hz, sizeof c.rate_hz);
  c.rate_stated = get_size(in, 1, 1) == 1;
  for (std::string* text : {&c.version, &c.variables}) {
    text->resize(get_size(in, kMaxAnswerTextBytes, 1));
    in.read(text->data(), text->size());
  }
  const std::size_t n = c.f[0].size();
  if (c.f[1].size() != n || c.f[2].size() != n || (!c.t.empty() && c.t.size() != n) ||
      !std::isfinite(c.rate_hz) || !(c.rate_hz > 0.0)) {
    throw std::runtime_error("the reading process's answer is not one it can give");
  }
  return c;
}

/// What the constructor reads: the file's forces, time, rate and what they were read from.
Contents read_contents(const fs::path& path, const std::string& name, const ColumnMap& columns,
                       double config_rate_hz, std::int64_t max_elements) {
  Reader r(path, max_elements);
  Contents c;
  c.version = r.version();
  std::array<Selector, 3> force;
  std::optional<Selector> time, rate;
  if (!columns.empty()) {
    for (int a = 0; a < 3; ++a) {
      force[static_cast<std::size_t>(a)] =
          parse_selector(columns.force(a), ColumnMap::kKeys[static_cast<std::size_t>(1 + a)], name);
    }
    if (columns.t().given()) {
      time = parse_selector(columns.t(), "t", name);
    }
    if (columns.fs().given()) {
      rate = parse_selector(columns.fs(), "fs", name);
    }
  } else {
    // By the usual names: three vectors, else a matrix with a dimension of 3.
    const std::optional<std::size_t> x =
        r.find_any({"fx", "fx_N", "force_x", "force_x_N", "forcex"});
    const std::optional<std::size_t> y =
        r.find_any({"fy", "fy_N", "force_y", "force_y_N", "forcey"});
    const std::optional<std::size_t> z =
        r.find_any({"fz", "fz_N", "force_z", "force_z_N", "forcez"});
    if (x && y && z) {
      force = {Selector::whole(r.name_of(*x)), Selector::whole(r.name_of(*y)),
               Selector::whole(r.name_of(*z))};
    } else if (const auto m =
                   r.find_any({"F", "force", "forces", "F_N", "force_N", "data"}, true)) {
      const auto d = r.dims_of(*m);
      const char slice = d[1] == 3 ? 'c' : 'r';  // N×3 by columns, 3×N by rows
      for (std::size_t a = 0; a < 3; ++a) {
        force[a] = Selector::whole(r.name_of(*m));
        force[a].slice = slice;
        force[a].k = a;
      }
    } else {
      throw std::runtime_error(name + ": no force variables found (variables: " + r.listing() +
                               "); name them with --columns fx=Fx,fy=Fy,fz=Fz or "
                               "fx=F(:,1),fy=F(:,2),fz=F(:,3) (and t=..., fs=...)");
    }
    if (const auto t = r.find_any({"t", "t_s", "time", "time_s"})) {
      time = Selector::whole(r.name_of(*t));
    }
    if (const auto fs = r.find_any({"fs", "sample_rate_hz", "sample_rate", "sampling_rate",
                                    "samplerate", "sampling_rate_hz", "rate_hz", "rate"})) {
      rate = Selector::whole(r.name_of(*fs));
    }
  }
  const char* keys[] = {"fx", "fy", "fz"};
  for (std::size_t a = 0; a < 3; ++a) {
    c.f[a] = r.read(force[a], keys[a]);
    c.variables += std::string(a > 0 ? " " : "") + keys[a] + "=" + force[a].text();
  }
  if (c.f[1].size() != c.f[0].size() || c.f[2].size() != c.f[0].size()) {
    throw std::runtime_error(
        name + ": the forces differ in length (fx " + std::to_string(c.f[0].size()) + ", fy " +
        std::to_string(c.f[1].size()) + ", fz " + std::to_string(c.f[2].size()) + " samples)");
  }
  if (time) {
    c.t = r.read(*time, "t");
    c.variables += " t=" + time->text();
    if (c.t.size() != c.f[0].size()) {
      throw std::runtime_error(name + ": t: " + time->text() + " has " +
                               std::to_string(c.t.size()) + " samples, the forces " +
                               std::to_string(c.f[0].size()));
    }
  }
  if (rate) {
    const std::vector<double> fs = r.read(*rate, "fs");
    c.variables += " fs=" + rate->text();
    if (fs.size() != 1 || !std::isfinite(fs[0]) || !(fs[0] > 0.0)) {
      throw std::runtime_error(name + ": fs: " + rate->text() +
                               " is not one positive finite number (the sample rate, Hz)");
    }
    c.rate_hz = fs[0];
    c.rate_stated = true;
  } else if (config_rate_hz > 0.0) {
    c.rate_hz = config_rate_hz;
  } else if (c.t.size() >= 2) {
    // From the time vector: the median step of its first samples.
    std::vector<double> dt;
    for (std::size_t k = 1; k < std::min<std::size_t>(c.t.size(), 4096); ++k) {
      if (c.t[k] > c.t[k - 1] && std::isfinite(c.t[k] - c.t[k - 1])) {
        dt.push_back(c.t[k] - c.t[k - 1]);
      }
    }
    if (!dt.empty()) {
      std::nth_element(dt.begin(), dt.begin() + static_cast<std::ptrdiff_t>(dt.size() / 2),
                       dt.end());
      c.rate_hz = 1.0 / dt[dt.size() / 2];
    }
  }
  if (!std::isfinite(c.rate_hz) || !(c.rate_hz > 0.0)) {
    throw std::runtime_error(name +
                             ": no sample rate: no rate variable (fs), no usable time "
                             "vector and none in the configuration (sample_rate_hz)");
  }
  // Without a time vector sample k is at k / rate: that must stay within the utime range.
  if (c.t.empty() && !(static_cast<double>(c.f[0].size()) / c.rate_hz * 1e6 <=
                       static_cast<double>(monitor::kMaxAbsUtime_us))) {
    throw std::runtime_error(name + ": a sample rate of " + number(c.rate_hz) + " Hz makes " +
                             std::to_string(c.f[0].size()) + " samples last beyond 2^53 µs");
  }
  return c;
}

/// read_contents() of a v7.3 file in a child process (shell/isolated_call.hpp): HDF5 1.10.8 reads
/// past its buffers on a damaged object header and allocates what it read there.
Contents read_contents_isolated(const fs::path& path, const std::string& name,
                                const ColumnMap& columns, double config_rate_hz,
                                std::int64_t max_elements) {
  // Bounded so that the sizes below cannot wrap.
  const auto elements = std::min(static_cast<std::size_t>(std::max<std::int64_t>(max_elements, 0)),
                                 std::numeric_limits<std::size_t>::max() / 128);
  // Four vectors, the two texts and the sizes and rate between them.
  const std::size_t max_answer = 4 * elements * sizeof(double) + 2 * kMaxAnswerTextBytes + 4096;
  // Up to four variables of the largest size as read, as doubles and the selected vectors, and
  // HDF5's own: 8 times the largest variable as doubles, and 512 MiB.
  const std::size_t budget = 8 * elements * sizeof(double) + (std::size_t{512} << 20);
  Contents c;
  const IsolatedResult r = run_isolated(
      [&](AnswerWriter& out) {
        write_contents(out, read_contents(path, name, columns, config_rate_hz, max_elements));
      },
      [&](AnswerReader& in) { c = read_answer(in, elements); }, max_answer, budget);
  switch (r.outcome) {
    case IsolatedResult::Outcome::kAnswer:
      return c;
    case IsolatedResult::Outcome::kError:  // the reader's errors name the file; others do not
      throw std::runtime_error(r.message.rfind(name + ": ", 0) == 0 ? r.message
                                                                    : name + ": " + r.message);
    case IsolatedResult::Outcome::kNotStarted:
      throw std::runtime_error(name + ": could not start the process that reads a v7.3 MAT-file (" +
                               r.message + ")");
    case IsolatedResult::Outcome::kFailed:
      break;
  }
  throw std::runtime_error(name +
                           ": this v7.3 MAT-file cannot be read (damaged: HDF5, reading it " +
                           "in a process of its own, " + r.message + ")");
}

}  // namespace

MatCutReader::MatCutReader(const fs::path& path, const ColumnMap& columns, double config_rate_hz,
                           OnBadSample on_bad_sample, std::int64_t max_elements)
    : name_(path.string()), on_bad_(std::move(on_bad_sample)) {
  try {
    quiet_matio();  // in this process, before any fork: HDF5 starts here once
  } catch (const std::runtime_error& e) {  // libmatio could not be loaded
    throw std::runtime_error(name_ + ": " + e.what());
  }
  const MatFileCheck check = check_mat_file(path, max_elements * 8);
  if (!check.problem.empty()) {
    throw std::runtime_error(name_ + ": " + check.problem);
  }
  Contents c = check.version == MatVersion::kV73
                   ? read_contents_isolated(path, name_, columns, config_rate_hz, max_elements)
                   : read_contents(path, name_, columns, config_rate_hz, max_elements);
  for (std::size_t a = 0; a < 3; ++a) {
    f_[a] = std::move(c.f[a]);
  }
  t_ = std::move(c.t);
  rate_hz_ = c.rate_hz;
  rate_stated_ = c.rate_stated;
  version_ = std::move(c.version);
  variables_ = std::move(c.variables);
}

bool MatCutReader::time_ok(std::size_t k) {
  const double t = t_[k];
  const auto index = static_cast<std::int64_t>(k) + 1;
  std::string problem;
  if (!std::isfinite(t)) {
    problem = "time is not finite (" + number(t) + ")";
  } else if (!(std::fabs(t * 1e6) <= static_cast<double>(monitor::kMaxAbsUtime_us))) {
    problem = "time " + number(t) + " s is out of range";
  } else if (have_last_ && !(t > last_t_)) {
    problem = "time " + number(t) + " s is not after t(" + std::to_string(last_index_) +
              ") = " + number(last_t_) + " s";
  } else if (have_last_ && k + 1 < t_.size() && t - last_t_ > 1.5 / rate_hz_ && t_[k + 1] < t &&
             t_[k + 1] > last_t_) {
    problem = "time " + number(t) + " s jumps ahead of the samples around it";
  }
  if (problem.empty()) {
    have_last_ = true;
    last_t_ = t;
    last_index_ = index;
    return true;
  }
  ++bad_samples_;
  if (on_bad_) {
    on_bad_(index, problem);
  }
  return false;
}

monitor::SampleBlock MatCutReader::next(std::size_t max_samples) {
  fx_.clear();
  fy_.clear();
  fz_.clear();
  const double dt = 1.0 / rate_hz_;
  double t0 = 0.0;
  while (fx_.size() < max_samples && next_ < f_[0].size()) {
    const std::size_t k = next_;
    double t = static_cast<double>(k) * dt;
    if (!t_.empty()) {
      if (!std::exchange(checked_, false) && !time_ok(k)) {
        ++next_;
        continue;
      }
      t = t_[k];
    }
    if (fx_.empty()) {
      t0 = t;
    } else if (std::fabs(t - (t0 + static_cast<double>(fx_.size()) * dt)) > 0.5 * dt) {
      checked_ = !t_.empty();  // time jumps: this sample (checked) opens the next block
      break;
    }
    fx_.push_back(f_[0][k]);
    fy_.push_back(f_[1][k]);
    fz_.push_back(f_[2][k]);
    ++next_;
  }
  monitor::SampleBlock b;
  b.utime_us = std::llround(t0 * 1e6);
  b.seq = seq_++;
  b.sample_rate_hz = rate_hz_;
  b.fx_N = fx_;
  b.fy_N = fy_;
  b.fz_N = fz_;
  return b;
}

}  // namespace millwatch::shell
