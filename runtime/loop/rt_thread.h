// Starting the loop's threads with their configured SCHED_FIFO priority and
// CPU pinning (threads.* in the configuration). Without the permission for
// real-time scheduling a thread starts with normal scheduling and a warning.
#pragma once

#include <pthread.h>

#include "runtime/base/expected.h"
#include "runtime/config/config.h"

namespace aprt {

Status start_thread(pthread_t* t, void* (*fn)(void*), void* arg, const ThreadConfig& tc,
                    const char* name);

}  // namespace aprt
