// A labelled LiDAR sequence (lidar_poses.txt + KITTI .bin / PCD scans, as
// `aprt_synth --lidar` writes it) as a frame source for `aprt run`, paced like
// the camera replay (drivers/input/replay/replay_pacer.h: fixed rate, as fast as
// taken, looping, a frame count). Each scan is read through the point gate
// (NaN/Inf dropped, clipped to the region, at most max_points) into the
// source's own buffer and copied into the frame slot: no allocation per scan.
// A scan that cannot be read is skipped with the reason.
#pragma once

#include <memory>

#include "drivers/input/frame_source.h"
#include "drivers/input/lidar/lidar_sequence.h"
#include "drivers/input/replay/replay_pacer.h"

namespace aprt {

class LidarReplaySource final : public FrameSource {
 public:
  static Expected<std::unique_ptr<LidarReplaySource>> open(const char* folder,
                                                           const ReplayPacing& pacing,
                                                           const ScanSourceOptions& scans);

  const char* name() const override { return "lidar replay"; }
  size_t max_frame_bytes() const override { return cloud_->capacity() * sizeof(Point); }
  Status start() override;
  SourceResult next(FrameBuffer* dst, int64_t timeout_ns) override;
  void stop() override {}
  const Error& error() const override { return error_; }
  void pace_with(const FrameSlot* slot) override { pacer_.pace_with(slot); }
  void note_taken(uint64_t n) override { pacer_.note_taken(n); }

  size_t size() const { return seq_->size(); }

 private:
  LidarReplaySource() = default;
  std::unique_ptr<LidarSequence> seq_;
  std::unique_ptr<PointCloud> cloud_;
  ScanSourceOptions options_;
  ReplayPacer pacer_;
  Error error_;
};

}  // namespace aprt
