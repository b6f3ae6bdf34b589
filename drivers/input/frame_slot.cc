#include "drivers/input/frame_slot.h"

#include <linux/futex.h>
#include <sys/mman.h>
#include <sys/syscall.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <new>

#include "runtime/base/check.h"

namespace aprt {

Expected<std::unique_ptr<FrameSlot>> FrameSlot::create(size_t capacity) {
  APRT_ENSURE(capacity > 0 && capacity <= (size_t(1) << 30), Errc::kInvalidArgument,
              "frame slot: capacity %zu bytes out of range", capacity);
  std::unique_ptr<FrameSlot> s(new (std::nothrow) FrameSlot());
  APRT_ENSURE(s != nullptr, Errc::kOutOfMemory, "frame slot: out of memory");
  const size_t each = (capacity + 63) / 64 * 64;
  void* p = mmap(nullptr, 3 * each, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  APRT_ENSURE(p != MAP_FAILED, Errc::kOutOfMemory, "frame slot: cannot map %zu bytes: %s", 3 * each,
              std::strerror(errno));
  std::memset(p, 0, 3 * each);  // prefault
  s->storage_ = static_cast<uint8_t*>(p);
  s->capacity_ = capacity;
  for (int i = 0; i < 3; ++i) {
    s->buffers_[i].data = s->storage_ + i * each;
    s->buffers_[i].capacity = capacity;
  }
  return s;
}

FrameSlot::~FrameSlot() {
  if (storage_) munmap(storage_, 3 * ((capacity_ + 63) / 64 * 64));
}

void FrameSlot::publish() noexcept {
  const uint32_t old = middle_.exchange(back_ | kFresh, std::memory_order_acq_rel);
  if (old & kFresh) dropped_.fetch_add(1, std::memory_order_relaxed);
  back_ = old & 0x3;
  published_.fetch_add(1, std::memory_order_acq_rel);
  syscall(SYS_futex, reinterpret_cast<uint32_t*>(&published_), FUTEX_WAKE_PRIVATE, 1, nullptr,
          nullptr, 0);
}

bool FrameSlot::take(const FrameBuffer** frame) noexcept {
  if (!(middle_.load(std::memory_order_acquire) & kFresh)) return false;
  const uint32_t old = middle_.exchange(front_, std::memory_order_acq_rel);
  front_ = old & 0x3;
  *frame = &buffers_[front_];
  return true;
}

uint32_t FrameSlot::wait(uint32_t seen, int64_t timeout_ns) noexcept {
  uint32_t now = published_.load(std::memory_order_acquire);
  if (now != seen || timeout_ns <= 0) return now;
  const timespec ts{time_t(timeout_ns / 1000000000), long(timeout_ns % 1000000000)};
  syscall(SYS_futex, reinterpret_cast<uint32_t*>(&published_), FUTEX_WAIT_PRIVATE, seen, &ts,
          nullptr, 0);
  return published_.load(std::memory_order_acquire);
}

}  // namespace aprt
