#include "shell/matio_library.hpp"

#include <dlfcn.h>

#include <mutex>
#include <stdexcept>
#include <string>
#include <type_traits>

#ifndef MILLWATCH_MATIO_SONAME
#error "MILLWATCH_MATIO_SONAME (libmatio's soname, found by shell/CMakeLists.txt) is not defined"
#endif

namespace millwatch::shell {
namespace {

std::string dl_problem() {
  const char* e = dlerror();
  return e != nullptr ? e : "unknown error";
}

MatioLibrary load() {
  // RTLD_NOW: a missing symbol shows here, not in the middle of a read.
  void* handle = dlopen(MILLWATCH_MATIO_SONAME, RTLD_NOW | RTLD_LOCAL);
  if (handle == nullptr) {
    throw std::runtime_error(std::string("cannot read MATLAB files: ") + dl_problem());
  }
  MatioLibrary m;
  auto take = [handle](auto& function, const char* name) {
    void* address = dlsym(handle, name);
    if (address == nullptr) {
      throw std::runtime_error(std::string("cannot read MATLAB files: ") + MILLWATCH_MATIO_SONAME +
                               " has no " + name + ": " + dl_problem());
    }
    function = reinterpret_cast<std::remove_reference_t<decltype(function)>>(address);
  };
  take(m.open, "Mat_Open");
  take(m.close, "Mat_Close");
  take(m.version, "Mat_GetVersion");
  take(m.rewind, "Mat_Rewind");
  take(m.read_next_info, "Mat_VarReadNextInfo");
  take(m.read, "Mat_VarRead");
  take(m.free, "Mat_VarFree");
  take(m.struct_field, "Mat_VarGetStructFieldByName");
  take(m.log_init, "Mat_LogInitFunc");
  // In matio's dependencies (dlsym on its handle searches them); absent if built without HDF5.
  if (void* address = dlsym(handle, "H5dont_atexit"); address != nullptr) {
    m.hdf5_dont_atexit = reinterpret_cast<int (*)()>(address);
  }
  return m;  // the handle stays open for the process's life
}

}  // namespace

const MatioLibrary& matio_library() {
  static std::once_flag once;
  static MatioLibrary library;
  std::call_once(once, [] { library = load(); });  // an exception: tried again next time
  return library;
}

}  // namespace millwatch::shell
