// Starting the loop's threads with their configured SCHED_FIFO priority and
// CPU pinning (threads.* in the configuration). Without the permission for
// real-time scheduling a thread starts with normal scheduling and a warning.
#pragma once

#include <pthread.h>

#include <cstdint>

#include "runtime/base/expected.h"
#include "runtime/config/config.h"

namespace aprt {

// stack_bytes: the thread's stack (0: the process default).
Status start_thread(pthread_t* t, void* (*fn)(void*), void* arg, const ThreadConfig& tc,
                    const char* name, size_t stack_bytes = 0);

// Joins `t` unless it is still running at `deadline_ns` (monotonic clock);
// false then, and the thread is left as it is. Polls pthread_tryjoin_np every
// millisecond rather than pthread_clockjoin_np: ThreadSanitizer (GCC 12)
// does not see the clockjoin as a join, and C libraries other than glibc lack
// it. Used at stop only, never on the real-time path.
bool join_thread_by(pthread_t t, int64_t deadline_ns);

}  // namespace aprt
