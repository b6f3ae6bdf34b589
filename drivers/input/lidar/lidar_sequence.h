// A labelled LiDAR sequence (issue #5): DIR/lidar_poses.txt ("name x y z qw qx
// qy qz", the sensor's pose in the map frame, as aprt_synth --lidar writes
// it) naming KITTI .bin or PCD scans relative to DIR. The list is read at
// open(); scans are read one at a time through ScanReader into a PointCloud,
// so every point passes the cloud's gate. For `aprt eval` and replay.
#pragma once

#include <memory>
#include <vector>

#include "drivers/input/lidar/point_cloud.h"
#include "drivers/input/lidar/scan_reader.h"
#include "drivers/input/replay/pose_list.h"

namespace aprt {

class LidarSequence {
 public:
  static Expected<std::unique_ptr<LidarSequence>> open(const char* folder);

  size_t size() const { return entries_.size(); }
  const ReplayEntry& entry(size_t i) const { return entries_[i]; }

  // Scan i into `cloud` (cleared first, points gated by `region`). A missing,
  // truncated or malformed scan is an error naming the file.
  Status read(size_t i, const PointRegion& region, PointCloud* cloud);

 private:
  LidarSequence() = default;
  char folder_[512] = {};
  std::vector<ReplayEntry> entries_;
  std::unique_ptr<ScanReader> reader_;
};

}  // namespace aprt
