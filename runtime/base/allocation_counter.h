// Counts heap allocations, so tests and `aprt bench` can prove that a stretch
// of code allocates nothing.
//
// Linking allocation_counter.cc replaces the global operator new/delete in
// every form (so that each allocation and its release meet one allocator)
// and, in builds without a sanitizer, interposes malloc, calloc, realloc,
// aligned_alloc, posix_memalign and memalign as well (the sanitizers own those
// symbols; there only C++ allocations are counted). Counting is one relaxed
// atomic increment per allocation.
#pragma once

#include <cstdint>

namespace aprt {

// Allocations (any thread) since the process started.
uint64_t allocation_count() noexcept;
// True when malloc-family calls are counted too (not under ASan).
bool allocation_counter_covers_malloc() noexcept;

class AllocationScope {
 public:
  AllocationScope() noexcept : start_(allocation_count()) {}
  uint64_t count() const noexcept { return allocation_count() - start_; }

 private:
  uint64_t start_;
};

}  // namespace aprt
