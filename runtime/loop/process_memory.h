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

// Where the process's resident memory is, from /proc/self/smaps (KiB): the
// engine's block, the program and its libraries (file mappings), thread
// stacks (anonymous mappings the size of threads.stack_kib, the main
// thread's [stack]) and the rest (heap, malloc's arena, libraries' own
// buffers). Reads through a stack buffer: no allocation, so the loop can
// sample it once it runs; false if /proc is unreadable.
struct MemoryBudget {
  uint64_t total_kb = 0;
  uint64_t locked_kb = 0;
  uint64_t engine_kb = 0;
  uint64_t code_kb = 0;
  uint64_t stacks_kb = 0;
  uint64_t other_kb = 0;
  uint32_t stacks = 0;  // mappings counted as thread stacks
};
bool measure_memory(const void* engine_block, size_t engine_bytes, size_t stack_bytes,
                    MemoryBudget* out);

// "RSS 28.9 MB = engine block 13.0 + program and libraries 13.2 + 7 stacks 0.4
// + heap and other 2.3; locked 12.7 MB" into buf.
void memory_budget_text(const MemoryBudget& b, char* buf, size_t n);

}  // namespace aprt
