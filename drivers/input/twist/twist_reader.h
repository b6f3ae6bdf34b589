// The vehicle's motion over DDS: a reader of
// geometry_msgs/msg/TwistWithCovarianceStamped on a ROS 2 topic (what
// Autoware's vehicle_velocity_converter publishes from the vehicle's
// wheel speed and yaw rate: "rt/<topic>", type
// "geometry_msgs::msg::dds_::TwistWithCovarianceStamped_"). Each sample
// becomes an OdometrySample (drivers/input/odometry.h): its header stamp,
// linear.x as the speed, angular.z as the yaw rate. A sample with a
// non-finite or absurd value, or an unset stamp, is refused and counted.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "drivers/input/odometry.h"
#include "runtime/base/expected.h"

namespace aprt {

struct TwistOptions {
  uint32_t domain = 0;
  std::string topic = "/sensing/vehicle_velocity_converter/twist_with_covariance";
  int depth = 50;
  bool reliable = true;  // Autoware publishes it reliable
  bool loopback_only = false;
};

struct TwistStats {
  uint64_t received = 0;  // valid samples taken
  uint64_t refused = 0;   // non-finite, absurd, or without a stamp
};

// A twist as it arrived: its stamp (ns since the epoch of the publisher's
// clock) and the two values the pose filter needs.
struct TwistSample {
  int64_t stamp_ns = 0;
  double speed_mps = 0, yaw_rate_radps = 0;
};

// Made by the DDS module (aprt_dds.so, drivers/dds/dds_module.h).
class TwistReader {
 public:
  static Expected<std::unique_ptr<TwistReader>> create(const TwistOptions& options);
  virtual ~TwistReader() = default;
  TwistReader(const TwistReader&) = delete;
  TwistReader& operator=(const TwistReader&) = delete;

  // Waits up to timeout_ns for twists, then takes up to `max` of them in
  // arrival order into `out`; returns how many.
  virtual int take(TwistSample* out, int max, int64_t timeout_ns) = 0;
  // Writers matched on the topic right now.
  virtual int publishers() const = 0;
  const TwistStats& stats() const { return stats_; }
  static const char* type_name() { return "geometry_msgs::msg::dds_::TwistWithCovarianceStamped_"; }

 protected:
  TwistReader() = default;
  TwistStats stats_;
};

}  // namespace aprt
