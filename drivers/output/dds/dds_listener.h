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

class DdsListener {
 public:
  // Same options as the publisher's (domain, topics, loopback profile, reliability).
  static Expected<std::unique_ptr<DdsListener>> create(const DdsOptions& options);
  ~DdsListener();
  DdsListener(const DdsListener&) = delete;
  DdsListener& operator=(const DdsListener&) = delete;

  // Waits up to timeout_ns for data, then takes up to n poses / statuses.
  int take_poses(DdsReceivedPose* out, int n, int64_t timeout_ns);
  int take_status(DdsReceivedStatus* out, int n);
  // Writers matched on the pose topic right now.
  int publishers() const;

 private:
  DdsListener() = default;
  int32_t participant_ = 0, pose_reader_ = 0, diag_reader_ = 0, waitset_ = 0, domain_ = 0;
};

}  // namespace aprt
