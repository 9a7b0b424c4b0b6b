#include "core/monitor/background_thread.hpp"

#if defined(__linux__)
#include <pthread.h>
#include <sched.h>
#endif

namespace millwatch::monitor {

bool make_this_thread_batch() {
#if defined(__linux__) && defined(SCHED_BATCH)
  const sched_param param{};  // priority 0: the only one SCHED_BATCH has
  return pthread_setschedparam(pthread_self(), SCHED_BATCH, &param) == 0;
#else
  return false;
#endif
}

}  // namespace millwatch::monitor
