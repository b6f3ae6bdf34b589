// A camera frame -- or a LiDAR scan -- in preallocated storage, with where
// and when it came from.
#pragma once

#include <cstddef>
#include <cstdint>

#include "drivers/input/odometry.h"
#include "runtime/base/image.h"
#include "runtime/base/lidar_point.h"

namespace aprt {

// What a FrameBuffer holds: pixels (width x height in `format`) or a scan
// (`points` LidarPoints, x y z intensity float32 in the sensor frame, every one
// through the point gate of drivers/input/lidar/point_cloud.h).
enum class FrameKind : uint8_t { kImage, kScan };

// A scan's gate counters (drivers/input/lidar/point_cloud.h ScanStats, per scan).
struct ScanInfo {
  uint32_t points = 0;
  uint32_t non_finite = 0, clipped = 0, over_capacity = 0;
};

struct FrameInfo {
  FrameKind kind = FrameKind::kImage;
  ScanInfo scan;           // kScan only
  uint64_t sequence = 0;   // per source, from 0; gaps are frames the source lost
  int64_t capture_ns = 0;  // CLOCK_MONOTONIC time of capture (driver timestamp)
  // The sensor's own stamp (ns since the epoch of its clock: a ROS header's),
  // when the source has one; 0: the publishers stamp from capture_ns.
  int64_t source_stamp_ns = 0;
  int width = 0, height = 0;
  PixelFormat format = PixelFormat::kRgb24;
  size_t stride = 0;    // bytes per row
  size_t bytes = 0;     // valid bytes in the buffer
  uint32_t source = 0;  // camera index
  // Ground truth, when the source has it (replay of a labelled sequence).
  bool has_truth = false;
  double truth_position[3] = {};
  double truth_orientation[4] = {1, 0, 0, 0};  // w x y z
  char name[128] = {};                         // e.g. the image file of a replayed frame
  // Where the vehicle's odometry put it at this frame, when the source knows
  // (a replay with odometry.txt; drivers/input/odometry.h): what the pose
  // filter carries its pose with between frames (runtime/pose/pose_filter.h).
  OdometryReading odometry;
};

struct FrameBuffer {
  FrameInfo info;
  uint8_t* data = nullptr;
  size_t capacity = 0;

  ImageView view() const { return {data, info.format, info.width, info.height, info.stride}; }
  const LidarPoint* points() const { return reinterpret_cast<const LidarPoint*>(data); }
};

}  // namespace aprt
