// The latest-frame mailbox between a capture thread and the inference thread:
// a triple buffer. The producer always has a buffer to write into and never
// waits; the consumer always gets the newest complete frame; a frame the
// consumer had not taken when a newer one was published is dropped and
// counted. Lock-free and wait-free on both sides (one atomic exchange each).
// All three buffers are allocated by create(); nothing is allocated after.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>

#include "drivers/input/frame.h"
#include "runtime/base/expected.h"

namespace aprt {

class FrameSlot {
 public:
  static_assert(std::atomic<uint32_t>::is_always_lock_free, "the slot needs lock-free atomics");

  // Three buffers of `capacity` bytes each.
  static Expected<std::unique_ptr<FrameSlot>> create(size_t capacity);
  ~FrameSlot();
  FrameSlot(const FrameSlot&) = delete;
  FrameSlot& operator=(const FrameSlot&) = delete;

  size_t capacity() const { return capacity_; }

  // Producer: the buffer to fill, then publish() it. @rt
  FrameBuffer& back() { return buffers_[back_]; }
  void publish() noexcept;

  // Consumer: true and *frame set if a frame newer than the last one taken is
  // ready; the frame stays valid until the next take(). @rt
  bool take(const FrameBuffer** frame) noexcept;

  // Waits up to timeout_ns for a publish after `seen` (a value of
  // published()), using a futex; returns the current published() count.
  uint32_t wait(uint32_t seen, int64_t timeout_ns) noexcept;
  uint32_t published() const noexcept { return published_.load(std::memory_order_acquire); }
  uint64_t dropped() const noexcept { return dropped_.load(std::memory_order_relaxed); }

 private:
  FrameSlot() = default;
  static constexpr uint32_t kFresh = 0x4;
  FrameBuffer buffers_[3];
  uint8_t* storage_ = nullptr;
  size_t capacity_ = 0;
  uint32_t back_ = 0;   // producer-owned
  uint32_t front_ = 2;  // consumer-owned
  std::atomic<uint32_t> middle_{1};
  std::atomic<uint32_t> published_{0};
  std::atomic<uint64_t> dropped_{0};
};

}  // namespace aprt
