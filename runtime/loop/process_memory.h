// The process's own memory beyond the engine's block, bounded before any
// thread starts: every thread's stack (ours and the DDS library's, which
// creates its threads with the process default) and malloc's arenas. With
// `threads.lock_memory` (mlockall) all of it is locked and resident, so each
// default 8 MiB stack and each 64 MiB per-thread malloc arena would cost
// that much locked memory (docs/configuration.md, "Memory").
#pragma once

#include <cstddef>

#include "runtime/config/config.h"

namespace aprt {

// The stack every thread gets: `threads.stack_kib`, four times that under
// AddressSanitizer or ThreadSanitizer (they enlarge every frame).
size_t thread_stack_bytes(const Config::Threads& t);

// Makes thread_stack_bytes() the default of every thread created from now on
// (pthread_setattr_default_np) and limits malloc to one arena (glibc's
// M_ARENA_MAX): aprt's threads do not allocate after start-up, so there is
// no contention to spread. Warnings, never errors, where the C library has
// neither. Call before the engine, the DDS participant or any thread starts.
void bound_process_memory(const Config::Threads& t);

}  // namespace aprt
