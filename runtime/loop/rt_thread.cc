#include "runtime/loop/rt_thread.h"

#include <sched.h>
#include <time.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace aprt {

Status start_thread(pthread_t* t, void* (*fn)(void*), void* arg, const ThreadConfig& tc,
                    const char* name, size_t stack_bytes) {
  pthread_attr_t attr;
  pthread_attr_init(&attr);
  if (stack_bytes > 0) pthread_attr_setstacksize(&attr, stack_bytes);
  if (tc.priority > 0) {
    sched_param sp{};
    sp.sched_priority = tc.priority;
    pthread_attr_setinheritsched(&attr, PTHREAD_EXPLICIT_SCHED);
    pthread_attr_setschedpolicy(&attr, SCHED_FIFO);
    pthread_attr_setschedparam(&attr, &sp);
  }
  int rc = pthread_create(t, &attr, fn, arg);
  if (rc == EPERM && tc.priority > 0) {
    std::fprintf(stderr,
                 "aprt run: warning: no permission for SCHED_FIFO priority %d on the %s thread "
                 "(needs CAP_SYS_NICE or an rtprio limit); running it with normal scheduling\n",
                 tc.priority, name);
    pthread_attr_setinheritsched(&attr, PTHREAD_INHERIT_SCHED);
    rc = pthread_create(t, &attr, fn, arg);
  }
  pthread_attr_destroy(&attr);
  if (rc != 0)
    return Error(Errc::kOutOfMemory, "run: cannot start the %s thread: %s", name,
                 std::strerror(rc));
  pthread_setname_np(*t, name);
  if (tc.cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(tc.cpu, &set);
    if (pthread_setaffinity_np(*t, sizeof set, &set) != 0) {
      std::fprintf(stderr, "aprt run: warning: cannot pin the %s thread to CPU %d\n", name, tc.cpu);
    }
  }
  return ok();
}

bool join_thread_by(pthread_t t, int64_t deadline_ns) {
  for (;;) {
    if (pthread_tryjoin_np(t, nullptr) == 0) return true;
    timespec now{};
    clock_gettime(CLOCK_MONOTONIC, &now);
    if (int64_t(now.tv_sec) * 1000000000 + now.tv_nsec >= deadline_ns) return false;
    const timespec pause{0, 1000000};
    nanosleep(&pause, nullptr);
  }
}

}  // namespace aprt
