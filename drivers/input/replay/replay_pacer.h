// When a replayed frame is due, for every replay source (camera images,
// LiDAR scans): at a fixed rate, at the recorded times, or as fast as the
// consumer takes frames (rate 0: the next frame is read only once the
// previous one was taken, so a demo loses none); optionally looping, and
// ending after a frame count. Waits at most the caller's timeout.
#pragma once

#include <time.h>

#include <atomic>
#include <cstddef>
#include <cstdint>

#include "drivers/input/frame_slot.h"
#include "drivers/input/frame_source.h"

namespace aprt {

struct ReplayPacing {
  double rate_hz = 10.0;  // 0: as fast as the consumer
  bool recorded = false;  // use the sequence's recorded times (times.txt)
  bool loop = false;
  uint64_t max_frames = 0;  // end of stream after this many frames (loops included); 0: no limit
};

class ReplayPacer {
 public:
  void configure(const ReplayPacing& p) { pacing_ = p; }
  const ReplayPacing& pacing() const { return pacing_; }

  void start(double first_time_s) {
    index_ = 0;
    start_ns_ = monotonic_ns();
    start_time_s_ = first_time_s;
  }
  // kFrame with *index (the frame to read now), or kTimeout (not due yet),
  // or kEndOfStream. time_of(i): the recorded time of frame i in seconds
  // (used with pacing.recorded only). A frame read successfully is then
  // delivered(), which numbers it; one that could not be read is not, so a
  // consumer-paced replay does not wait for a frame that never came.
  template <class TimeOf>
  SourceResult next(size_t size, TimeOf time_of, int64_t timeout_ns, size_t* index) {
    if (pacing_.max_frames > 0 && sequence_ >= pacing_.max_frames) {
      return SourceResult::kEndOfStream;
    }
    if (index_ >= size) {
      if (!pacing_.loop || size == 0) return SourceResult::kEndOfStream;
      index_ = 0;
      start_ns_ = monotonic_ns() - (pacing_.rate_hz > 0 ? int64_t(1e9 / pacing_.rate_hz) : 0);
      start_time_s_ = time_of(0);
    }
    int64_t due = 0;
    if (pacing_.recorded) {
      due = start_ns_ + int64_t((time_of(index_) - start_time_s_) * 1e9);
    } else if (pacing_.rate_hz > 0) {
      due = start_ns_ + int64_t(double(index_) * 1e9 / pacing_.rate_hz);
    } else if (paced_by_ && sequence_ > taken_.load(std::memory_order_acquire)) {
      // As fast as the consumer: wait until it took the previous frame.
      const timespec ts{0, long(timeout_ns < 1000000 ? timeout_ns : 1000000)};
      nanosleep(&ts, nullptr);
      return SourceResult::kTimeout;
    }
    const int64_t now = monotonic_ns();
    if (due > now) {
      const int64_t wait = due - now < timeout_ns ? due - now : timeout_ns;
      const timespec ts{time_t(wait / 1000000000), long(wait % 1000000000)};
      nanosleep(&ts, nullptr);
      if (monotonic_ns() < due) return SourceResult::kTimeout;
    }
    *index = index_++;
    return SourceResult::kFrame;
  }
  // The delivered frame's sequence number (its count in the run, from 0).
  uint64_t delivered() { return sequence_++; }

  // Rate 0: the slot whose consumption paces the replay, and how many frames
  // its consumer has taken.
  void pace_with(const FrameSlot* slot) { paced_by_ = slot; }
  void note_taken(uint64_t n) { taken_.store(n, std::memory_order_release); }

 private:
  ReplayPacing pacing_;
  size_t index_ = 0;
  uint64_t sequence_ = 0;
  int64_t start_ns_ = 0;
  double start_time_s_ = 0;
  const FrameSlot* paced_by_ = nullptr;
  std::atomic<uint64_t> taken_{0};
};

}  // namespace aprt
