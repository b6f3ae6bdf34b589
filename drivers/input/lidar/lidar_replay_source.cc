#include "drivers/input/lidar/lidar_replay_source.h"

#include <cstdio>
#include <cstring>
#include <new>

namespace aprt {

Expected<std::unique_ptr<LidarReplaySource>> LidarReplaySource::open(
    const char* folder, const ReplayPacing& pacing, const ScanSourceOptions& scans) {
  if (pacing.recorded) {
    return Error(Errc::kInvalidArgument,
                 "lidar replay: %s: LiDAR sequences have no recorded times; use a fixed rate_hz "
                 "(or 0: as fast as inference takes scans)",
                 folder);
  }
  std::unique_ptr<LidarReplaySource> s(new (std::nothrow) LidarReplaySource());
  if (!s) return Error(Errc::kOutOfMemory, "lidar replay: out of memory");
  auto seq = LidarSequence::open(folder);
  if (!seq) return seq.error();
  auto cloud = PointCloud::create(scans.max_points);
  if (!cloud) return cloud.error();
  s->seq_ = std::move(seq.value());
  s->cloud_ = std::move(cloud.value());
  s->options_ = scans;
  s->pacer_.configure(pacing);
  return s;
}

Status LidarReplaySource::start() {
  pacer_.start(0.0);
  return ok();
}

SourceResult LidarReplaySource::next(FrameBuffer* dst, int64_t timeout_ns) {
  size_t i = 0;
  const SourceResult r = pacer_.next(
      seq_->size(), [](size_t) { return 0.0; }, timeout_ns, &i);
  if (r != SourceResult::kFrame) return r;
  if (Status s = seq_->read(i, options_.region, cloud_.get()); !s) {
    error_ = s.error();
    return SourceResult::kSkipped;
  }
  copy_scan(*cloud_, dst);
  FrameInfo& f = dst->info;
  f.sequence = pacer_.delivered();
  f.capture_ns = monotonic_ns();
  const ReplayEntry& e = seq_->entry(i);
  f.has_truth = true;
  for (int k = 0; k < 3; ++k) f.truth_position[k] = e.position[k];
  for (int k = 0; k < 4; ++k) f.truth_orientation[k] = e.orientation[k];
  std::snprintf(f.name, sizeof f.name, "%s", e.name);
  return SourceResult::kFrame;
}

}  // namespace aprt
