#include "drivers/replay/replay_source.h"

#include <time.h>

#include <new>

namespace aprt {

Expected<std::unique_ptr<ReplaySource>> ReplaySource::open(const char* folder,
                                                           const ReplayPacing& p) {
  std::unique_ptr<ReplaySource> s(new (std::nothrow) ReplaySource());
  if (!s) return Error(Errc::kOutOfMemory, "replay: out of memory");
  auto r = DeeplocReplay::open(folder);
  if (!r) return r.error();
  if (p.recorded && !r.value()->has_times()) {
    return Error(Errc::kInvalidArgument,
                 "replay: %s has no complete times.txt, so it cannot be replayed at the recorded "
                 "rate (use a fixed rate_hz)",
                 folder);
  }
  s->replay_ = std::move(r.value());
  s->pacing_ = p;
  return s;
}

Status ReplaySource::start() {
  index_ = 0;
  start_ns_ = monotonic_ns();
  start_time_s_ = replay_->entry(0).time_s;
  return ok();
}

SourceResult ReplaySource::next(FrameBuffer* dst, int64_t timeout_ns) {
  if (pacing_.max_frames > 0 && sequence_ >= pacing_.max_frames) return SourceResult::kEndOfStream;
  if (index_ >= replay_->size()) {
    if (!pacing_.loop) return SourceResult::kEndOfStream;
    index_ = 0;
    start_ns_ = monotonic_ns() - (pacing_.rate_hz > 0 ? int64_t(1e9 / pacing_.rate_hz) : 0);
    start_time_s_ = replay_->entry(0).time_s;
  }
  // When is this frame due?
  int64_t due = 0;
  if (pacing_.recorded) {
    due = start_ns_ + int64_t((replay_->entry(index_).time_s - start_time_s_) * 1e9);
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
  const size_t i = index_++;
  const Status s = replay_->read(i, dst, sequence_++, monotonic_ns());
  if (!s) {
    error_ = s.error();
    return SourceResult::kSkipped;
  }
  return SourceResult::kFrame;
}

}  // namespace aprt
