// Single-producer single-consumer ring of fixed capacity: push() fails when
// full (the caller counts the drop), pop() fails when empty. Lock-free; no
// allocation after construction (storage is part of the object).
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>

namespace aprt {

template <class T, size_t N>
class SpscRing {
  static_assert((N & (N - 1)) == 0, "capacity must be a power of two");
  static_assert(std::atomic<size_t>::is_always_lock_free, "the ring needs lock-free atomics");

 public:
  bool push(const T& v) noexcept {
    const size_t h = head_.load(std::memory_order_relaxed);
    if (h - tail_.load(std::memory_order_acquire) == N) return false;
    items_[h & (N - 1)] = v;
    head_.store(h + 1, std::memory_order_release);
    return true;
  }
  bool pop(T* out) noexcept {
    const size_t t = tail_.load(std::memory_order_relaxed);
    if (t == head_.load(std::memory_order_acquire)) return false;
    *out = items_[t & (N - 1)];
    tail_.store(t + 1, std::memory_order_release);
    return true;
  }
  size_t size() const noexcept {
    return head_.load(std::memory_order_acquire) - tail_.load(std::memory_order_acquire);
  }

 private:
  T items_[N];
  alignas(64) std::atomic<size_t> head_{0};
  alignas(64) std::atomic<size_t> tail_{0};
};

}  // namespace aprt
