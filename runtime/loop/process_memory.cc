#include "runtime/loop/process_memory.h"

#include <pthread.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace aprt {

size_t thread_stack_bytes(const Config::Threads& t) {
  size_t bytes = size_t(t.stack_kib) * 1024;
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  bytes *= 4;
#endif
  return bytes;
}

void bound_process_memory(const Config::Threads& t) {
#if defined(__GLIBC__)
  pthread_attr_t attr;
  if (pthread_attr_init(&attr) == 0) {
    const int rc = pthread_attr_setstacksize(&attr, thread_stack_bytes(t));
    if (rc != 0 || pthread_setattr_default_np(&attr) != 0) {
      std::fprintf(stderr, "aprt run: warning: cannot set the threads' stack size to %d KiB (%s)\n",
                   t.stack_kib, std::strerror(rc ? rc : EINVAL));
    }
    pthread_attr_destroy(&attr);
  }
  if (mallopt(M_ARENA_MAX, 1) != 1) {
    std::fprintf(stderr, "aprt run: warning: cannot limit malloc to one arena\n");
  }
#else
  (void)t;  // other C libraries: stacks set per thread by start_thread only
#endif
}

}  // namespace aprt
