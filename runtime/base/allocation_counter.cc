#include "runtime/base/allocation_counter.h"

#include <atomic>
#include <cstddef>
#include <cstdlib>
#include <new>

#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define APRT_ASAN 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define APRT_ASAN 1
#endif

namespace {
std::atomic<uint64_t> g_allocations{0};
inline void count() {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
}
}  // namespace

namespace aprt {
uint64_t allocation_count() noexcept {
  return g_allocations.load(std::memory_order_relaxed);
}
#ifdef APRT_ASAN
bool allocation_counter_covers_malloc() noexcept {
  return false;
}
#else
bool allocation_counter_covers_malloc() noexcept {
  return true;
}
#endif
}  // namespace aprt

#ifndef APRT_ASAN
extern "C" {
void* __libc_malloc(size_t);
void* __libc_calloc(size_t, size_t);
void* __libc_realloc(void*, size_t);
void* __libc_memalign(size_t, size_t);
void __libc_free(void*);

void* malloc(size_t n) {
  count();
  return __libc_malloc(n);
}
void* calloc(size_t n, size_t m) {
  count();
  return __libc_calloc(n, m);
}
void* realloc(void* p, size_t n) {
  count();
  return __libc_realloc(p, n);
}
void* memalign(size_t a, size_t n) {
  count();
  return __libc_memalign(a, n);
}
void* aligned_alloc(size_t a, size_t n) {
  count();
  return __libc_memalign(a, n);
}
int posix_memalign(void** out, size_t a, size_t n) {
  count();
  void* p = __libc_memalign(a, n);
  if (!p) return 12;  // ENOMEM
  *out = p;
  return 0;
}
void free(void* p) {
  __libc_free(p);
}
}
#define APRT_RAW_ALLOC(n) __libc_malloc(n)
#define APRT_RAW_ALIGNED(a, n) __libc_memalign(a, n)
#define APRT_RAW_FREE(p) __libc_free(p)
#else
#define APRT_RAW_ALLOC(n) std::malloc(n)
#define APRT_RAW_ALIGNED(a, n) std::aligned_alloc(a, ((n) + (a)-1) / (a) * (a))
#define APRT_RAW_FREE(p) std::free(p)
#endif

namespace {
void* counted_new(size_t n) {
  count();
  void* p = APRT_RAW_ALLOC(n ? n : 1);
  if (!p) std::abort();  // built without exceptions: no bad_alloc to throw
  return p;
}
void* counted_new_aligned(size_t n, std::align_val_t a) {
  count();
  void* p = APRT_RAW_ALIGNED(static_cast<size_t>(a), n ? n : 1);
  if (!p) std::abort();
  return p;
}
}  // namespace

void* operator new(size_t n) {
  return counted_new(n);
}
void* operator new[](size_t n) {
  return counted_new(n);
}
void* operator new(size_t n, const std::nothrow_t&) noexcept {
  count();
  return APRT_RAW_ALLOC(n ? n : 1);
}
void* operator new[](size_t n, const std::nothrow_t&) noexcept {
  count();
  return APRT_RAW_ALLOC(n ? n : 1);
}
void* operator new(size_t n, std::align_val_t a) {
  return counted_new_aligned(n, a);
}
void* operator new[](size_t n, std::align_val_t a) {
  return counted_new_aligned(n, a);
}
void operator delete(void* p) noexcept {
  APRT_RAW_FREE(p);
}
void operator delete[](void* p) noexcept {
  APRT_RAW_FREE(p);
}
void operator delete(void* p, size_t) noexcept {
  APRT_RAW_FREE(p);
}
void operator delete[](void* p, size_t) noexcept {
  APRT_RAW_FREE(p);
}
void operator delete(void* p, std::align_val_t) noexcept {
  APRT_RAW_FREE(p);
}
void operator delete[](void* p, std::align_val_t) noexcept {
  APRT_RAW_FREE(p);
}
void operator delete(void* p, size_t, std::align_val_t) noexcept {
  APRT_RAW_FREE(p);
}
void operator delete[](void* p, size_t, std::align_val_t) noexcept {
  APRT_RAW_FREE(p);
}
void* operator new(size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  count();
  return APRT_RAW_ALIGNED(static_cast<size_t>(a), n ? n : 1);
}
void* operator new[](size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  count();
  return APRT_RAW_ALIGNED(static_cast<size_t>(a), n ? n : 1);
}
void operator delete(void* p, const std::nothrow_t&) noexcept {
  APRT_RAW_FREE(p);
}
void operator delete[](void* p, const std::nothrow_t&) noexcept {
  APRT_RAW_FREE(p);
}
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept {
  APRT_RAW_FREE(p);
}
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept {
  APRT_RAW_FREE(p);
}
