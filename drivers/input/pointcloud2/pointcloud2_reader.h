// LiDAR input over DDS (issue #5): a reader of sensor_msgs/msg/PointCloud2 on
// a ROS 2 topic ("rt/<topic>", type "sensor_msgs::msg::dds_::PointCloud2_",
// ROS 2's sensor-data QoS: best effort, keep last), that decodes the newest
// cloud into a preallocated PointCloud. Older clouds waiting behind it are
// dropped and counted ("superseded": a localiser wants the latest scan); a
// malformed cloud is dropped with its reason counted and kept for the log,
// and the caller keeps its last good scan.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "drivers/input/lidar/point_cloud.h"
#include "drivers/input/pointcloud2/pointcloud2_decode.h"
#include "runtime/base/expected.h"

namespace aprt {

struct PointCloud2Options {
  uint32_t domain = 0;
  std::string topic = "/points_raw";  // ROS name; "rt" is prepended
  int depth = 5;
  bool reliable = false;       // ROS 2 sensor data QoS is best effort
  bool loopback_only = false;  // discovery on 127.0.0.1 only (tests, HIL)
};

struct PointCloud2Stats {
  uint64_t received = 0;    // valid samples taken
  uint64_t decoded = 0;     // handed to the caller
  uint64_t superseded = 0;  // a newer cloud was already waiting
  uint64_t refused[size_t(CloudRefusal::kCount)] = {};
  char last_refusal[Error::kCapacity] = {};
};

// Made by the DDS module (aprt_dds.so, drivers/dds/dds_module.h),
// like DdsPublisher.
class PointCloud2Reader {
 public:
  static constexpr int kMaxFields = 64;

  static Expected<std::unique_ptr<PointCloud2Reader>> create(const PointCloud2Options& options);
  virtual ~PointCloud2Reader() = default;
  PointCloud2Reader(const PointCloud2Reader&) = delete;
  PointCloud2Reader& operator=(const PointCloud2Reader&) = delete;

  // Waits up to timeout_ns for clouds, then decodes the newest into `out`.
  // true: `out` holds it and *stamp_ns its header stamp; false: nothing new
  // (or only malformed clouds: see stats()), `out` untouched.
  virtual bool take_latest(const PointRegion& region, PointCloud* out, int64_t timeout_ns,
                           int64_t* stamp_ns) = 0;
  const PointCloud2Stats& stats() const { return stats_; }
  // Writers matched on the topic right now.
  virtual int publishers() const = 0;
  // ROS 2's name of the type on the wire (the module checks its generated type against it).
  static const char* type_name() { return "sensor_msgs::msg::dds_::PointCloud2_"; }

 protected:
  PointCloud2Reader() = default;
  PointCloud2Stats stats_;
};

}  // namespace aprt
