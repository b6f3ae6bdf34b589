// Live LiDAR over DDS as a frame source for `aprt run` (issue #5): the newest
// sensor_msgs/msg/PointCloud2 on a ROS 2 topic (drivers/input/pointcloud2/pointcloud2_reader.h:
// any point layout, malformed clouds refused and counted), through the point
// gate into the frame slot. The frame's capture time is its arrival
// (CLOCK_MONOTONIC, for frame age); the cloud's header stamp travels with it
// and stamps the published pose. No publisher for a while is a timeout, not a
// failure: the supervisor sees the stale input and flags it.
#pragma once

#include <memory>

#include "drivers/input/frame_source.h"
#include "drivers/input/lidar/point_cloud.h"
#include "drivers/input/pointcloud2/pointcloud2_reader.h"

namespace aprt {

class PointCloud2Source final : public FrameSource {
 public:
  static Expected<std::unique_ptr<PointCloud2Source>> create(const PointCloud2Options& dds,
                                                             const ScanSourceOptions& scans);

  const char* name() const override { return "PointCloud2"; }
  size_t max_frame_bytes() const override { return cloud_->capacity() * sizeof(Point); }
  Status start() override { return ok(); }
  SourceResult next(FrameBuffer* dst, int64_t timeout_ns) override;
  void stop() override {}
  const Error& error() const override { return error_; }

  const PointCloud2Stats& stats() const { return reader_->stats(); }

 private:
  PointCloud2Source() = default;
  std::unique_ptr<PointCloud2Reader> reader_;
  std::unique_ptr<PointCloud> cloud_;
  ScanSourceOptions options_;
  Error error_;
  uint64_t sequence_ = 0;
  uint64_t refused_seen_ = 0;
};

}  // namespace aprt
