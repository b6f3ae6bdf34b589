// The pose and the runtime's status on DDS (Cyclone DDS C API), in ROS 2's
// wire naming: geometry_msgs/msg/PoseWithCovarianceStamped on rt/<topic> and
// diagnostic_msgs/msg/DiagnosticArray on rt/diagnostics. Samples and their
// strings are preallocated at create(); publishing allocates nothing of ours
// (Cyclone serialises into its own buffers).
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "drivers/output/dds/dds_discovery.h"
#include "runtime/base/expected.h"

namespace aprt {

struct DdsOptions {
  uint32_t domain = 0;
  std::string pose_topic = "/aprt/pose_with_covariance";  // ROS name; "rt" is prepended
  std::string diagnostics_topic = "/diagnostics";
  std::string frame_id = "map";
  bool reliable = true;  // ROS default QoS: reliable, keep last 10, volatile
  int depth = 10;
  bool loopback_only = false;  // discovery on 127.0.0.1 only (tests, HIL)
  // At create(), wait up to this long until the participants already in the
  // domain have told their endpoints (dds_discovery.h); 0: no wait.
  int discovery_wait_ms = 1500;
};

struct DdsPose {
  int64_t stamp_ns;  // source frame capture time, since the Unix epoch
  double position[3];
  double orientation[4];  // w x y z
  double covariance[36];
};

// Made by the DDS module (aprt_dds.so, drivers/dds/dds_module.h), opened by the first
// create() of any DDS endpoint: a program that configures no DDS loads none
// of Cyclone DDS's libraries (OpenSSL, iceoryx: ~3 MiB resident).
class DdsPublisher {
 public:
  static Expected<std::unique_ptr<DdsPublisher>> create(const DdsOptions& options);
  virtual ~DdsPublisher() = default;
  DdsPublisher(const DdsPublisher&) = delete;
  DdsPublisher& operator=(const DdsPublisher&) = delete;

  virtual Status publish_pose(const DdsPose& pose) noexcept = 0;
  // level: 0 OK, 1 WARN, 2 ERROR, 3 STALE. `message` is copied (truncated to 127 chars).
  virtual Status publish_status(int64_t stamp_ns, uint8_t level, const char* message,
                                const char* const* keys, const char* const* values,
                                int count) noexcept = 0;

  // ROS 2's name of the pose type on the wire (the module checks its
  // generated type against it).
  static const char* pose_type_name() {
    return "geometry_msgs::msg::dds_::PoseWithCovarianceStamped_";
  }
  // What the start-up discovery wait found (DdsOptions::discovery_wait_ms).
  const DdsDiscoveryReport& discovery() const { return discovery_; }

 protected:
  DdsPublisher() = default;
  DdsDiscoveryReport discovery_;
};

}  // namespace aprt
