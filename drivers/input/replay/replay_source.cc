#include "drivers/input/replay/replay_source.h"

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
  s->pacer_.configure(p);
  return s;
}

Status ReplaySource::start() {
  pacer_.start(replay_->entry(0).time_s);
  return ok();
}

SourceResult ReplaySource::next(FrameBuffer* dst, int64_t timeout_ns) {
  size_t i = 0;
  const SourceResult r = pacer_.next(
      replay_->size(), [this](size_t k) { return replay_->entry(k).time_s; }, timeout_ns, &i);
  if (r != SourceResult::kFrame) return r;
  const Status s = replay_->read(i, dst, 0, monotonic_ns());
  if (!s) {
    error_ = s.error();
    return SourceResult::kSkipped;
  }
  dst->info.sequence = pacer_.delivered();
  // A loop's restart begins new odometry epochs: no motion across it.
  if (have_previous_ && i < previous_) ++loops_;
  previous_ = i;
  have_previous_ = true;
  dst->info.odometry = replay_->reading(i);
  dst->info.odometry.epoch += loops_ * replay_->epochs();
  return SourceResult::kFrame;
}

}  // namespace aprt
