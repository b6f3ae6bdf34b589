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

class DdsPublisher {
 public:
  static Expected<std::unique_ptr<DdsPublisher>> create(const DdsOptions& options);
  ~DdsPublisher();
  DdsPublisher(const DdsPublisher&) = delete;
  DdsPublisher& operator=(const DdsPublisher&) = delete;

  Status publish_pose(const DdsPose& pose) noexcept;
  // level: 0 OK, 1 WARN, 2 ERROR, 3 STALE. `message` is copied (truncated to 127 chars).
  Status publish_status(int64_t stamp_ns, uint8_t level, const char* message,
                        const char* const* keys, const char* const* values, int count) noexcept;

  static const char* pose_type_name();
  int32_t participant() const { return participant_; }
  // What the start-up discovery wait found (DdsOptions::discovery_wait_ms).
  const DdsDiscoveryReport& discovery() const { return discovery_; }

 private:
  DdsPublisher() = default;
  int32_t participant_ = 0, pose_writer_ = 0, diag_writer_ = 0, domain_ = 0;
  char frame_id_[64] = {};
  DdsDiscoveryReport discovery_;
  struct Samples;
  std::unique_ptr<Samples> samples_;
};

}  // namespace aprt
