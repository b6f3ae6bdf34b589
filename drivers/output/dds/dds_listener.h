// The receiving side of aprt's DDS output, as the localisation stack sees
// it: a reader of the pose topic and of the diagnostics topic with ROS 2's
// names and types (`aprt ddsdump`, the HIL rig, the tests). Not on aprt's
// real-time path: takes copy samples out of Cyclone's loans.
#pragma once

#include <cstdint>
#include <memory>

#include "drivers/output/dds/dds_publisher.h"

namespace aprt {

struct DdsReceivedPose {
  int64_t stamp_ns;
  char frame_id[64];
  double position[3];
  double orientation[4];  // w x y z
  double covariance[36];
};

struct DdsReceivedStatus {
  int64_t stamp_ns;
  uint8_t level;  // 0 OK, 1 WARN, 2 ERROR, 3 STALE
  char message[128];
  char state[32];  // the "state" key's value, if present
};

// Made by the DDS module, like DdsPublisher.
class DdsListener {
 public:
  // Same options as the publisher's (domain, topics, loopback profile, reliability).
  static Expected<std::unique_ptr<DdsListener>> create(const DdsOptions& options);
  virtual ~DdsListener() = default;
  DdsListener(const DdsListener&) = delete;
  DdsListener& operator=(const DdsListener&) = delete;

  // Waits up to timeout_ns for data, then takes up to n poses / statuses.
  virtual int take_poses(DdsReceivedPose* out, int n, int64_t timeout_ns) = 0;
  virtual int take_status(DdsReceivedStatus* out, int n) = 0;
  // Writers matched on the pose topic right now.
  virtual int publishers() const = 0;

 protected:
  DdsListener() = default;
};

}  // namespace aprt
