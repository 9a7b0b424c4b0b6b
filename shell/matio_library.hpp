#pragma once
// libmatio, loaded with dlopen when the first .mat file is read. Linked in, it and what HDF5
// brings along (curl, TLS, Kerberos, LDAP: ~30 libraries) cost every start of millwatch and
// millwatchd ~5 ms of loading and relocating, for a format most runs never read. matio.h still
// gives the types and the functions' signatures (each pointer is decltype(&Mat_...)).

#include <matio.h>

namespace millwatch::shell {

/// The matio functions mat_cut_reader uses.
struct MatioLibrary {
  decltype(&Mat_Open) open = nullptr;
  decltype(&Mat_Close) close = nullptr;
  decltype(&Mat_GetVersion) version = nullptr;
  decltype(&Mat_Rewind) rewind = nullptr;
  decltype(&Mat_VarReadNextInfo) read_next_info = nullptr;
  decltype(&Mat_VarRead) read = nullptr;
  decltype(&Mat_VarFree) free = nullptr;
  decltype(&Mat_VarGetStructFieldByName) struct_field = nullptr;
  decltype(&Mat_LogInitFunc) log_init = nullptr;
  /// HDF5's H5dont_atexit (libmatio's HDF5, for v7.3 files); null if matio has none.
  int (*hdf5_dont_atexit)() = nullptr;
};

/// libmatio's functions, loaded by the first call (any thread; the library stays loaded).
/// @throws std::runtime_error "cannot read MATLAB files: libmatio.so.N: ..." if the library or
///         one of the functions is missing
const MatioLibrary& matio_library();

}  // namespace millwatch::shell
