// A LiDAR scan in preallocated storage (issue #5): x, y, z, intensity as
// float32 in the sensor frame, metres. Bounded work per scan: at most
// `capacity` points (from the configuration); what does not fit is dropped
// and counted, never grown. Every point passes one gate on the way in
// (add()): NaN/Inf dropped and counted, coordinates outside the configured
// region clipped to it and counted -- an absurd value never reaches a kernel.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>

#include "drivers/input/frame.h"
#include "runtime/base/expected.h"
#include "runtime/base/lidar_point.h"

namespace aprt {

using Point = LidarPoint;

// Where points may be: anything outside is clipped to the box.
struct PointRegion {
  float x_min = -200, x_max = 200, y_min = -200, y_max = 200, z_min = -20, z_max = 40;
};

struct ScanStats {
  uint64_t read = 0;           // points the source offered
  uint64_t non_finite = 0;     // dropped: NaN or Inf in x, y or z
  uint64_t clipped = 0;        // kept, moved onto the region's boundary
  uint64_t over_capacity = 0;  // dropped: the scan had more points than the buffer
};

class PointCloud {
 public:
  static Expected<std::unique_ptr<PointCloud>> create(size_t capacity);
  ~PointCloud();
  PointCloud(const PointCloud&) = delete;
  PointCloud& operator=(const PointCloud&) = delete;

  // A new scan: no points, counters zero. @rt
  void clear(const PointRegion& region) noexcept {
    size_ = 0;
    stats_ = ScanStats{};
    region_ = region;
  }
  // @rt: one point through the gate.
  void add(float x, float y, float z, float intensity) noexcept;

  const Point* points() const { return points_; }
  Point* points() { return points_; }
  size_t size() const { return size_; }
  size_t capacity() const { return capacity_; }
  const ScanStats& stats() const { return stats_; }

 private:
  PointCloud() = default;
  Point* points_ = nullptr;
  size_t size_ = 0, capacity_ = 0;
  ScanStats stats_;
  PointRegion region_;
};

struct ScanSourceOptions {
  size_t max_points = 200000;
  PointRegion region;
};

// A scan's points into a frame buffer: kind, counts and bytes set, the gate's
// counters kept. The buffer holds max_frame_bytes() of the source.
void copy_scan(const PointCloud& cloud, FrameBuffer* dst);

}  // namespace aprt
