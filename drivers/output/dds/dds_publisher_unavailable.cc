// Built instead of dds_publisher.cc and dds_listener.cc when Cyclone DDS is not found for the
// target: DDS output then fails at start with a reason, like any other
// unavailable output, and the rest of aprt runs.
#include "drivers/output/dds/dds_listener.h"
#include "drivers/output/dds/dds_publisher.h"

namespace aprt {

struct DdsPublisher::Samples {};

Expected<std::unique_ptr<DdsPublisher>> DdsPublisher::create(const DdsOptions&) {
  return Error(Errc::kUnsupported,
               "dds: this build has no DDS (Cyclone DDS was not found when it was configured; "
               "install cyclonedds-dev for the target and rebuild)");
}

DdsPublisher::~DdsPublisher() = default;

Status DdsPublisher::publish_pose(const DdsPose&) noexcept {
  return Error(Errc::kUnsupported, "dds: not built");
}

Status DdsPublisher::publish_status(int64_t, uint8_t, const char*, const char* const*,
                                    const char* const*, int) noexcept {
  return Error(Errc::kUnsupported, "dds: not built");
}

const char* DdsPublisher::pose_type_name() {
  return "";
}

Expected<std::unique_ptr<DdsListener>> DdsListener::create(const DdsOptions&) {
  return Error(Errc::kUnsupported,
               "dds: this build has no DDS (Cyclone DDS was not found when it was configured)");
}
DdsListener::~DdsListener() = default;
int DdsListener::take_poses(DdsReceivedPose*, int, int64_t) {
  return 0;
}
int DdsListener::take_status(DdsReceivedStatus*, int) {
  return 0;
}
int DdsListener::publishers() const {
  return 0;
}

}  // namespace aprt
