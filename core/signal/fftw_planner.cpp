#include "core/signal/fftw_planner.hpp"

namespace millwatch::signal {

std::mutex& fftw_planner_mutex() {
  static std::mutex m;
  return m;
}

}  // namespace millwatch::signal
