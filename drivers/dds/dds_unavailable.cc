// Built instead of dds_publisher.cc when Cyclone DDS is not found for the
// target: DDS output then fails at start with a reason, like any other
// unavailable output, and the rest of aprt runs.
#include "drivers/dds/dds_listener.h"
#include "drivers/dds/dds_publisher.h"
#include "drivers/dds/pointcloud2_reader.h"

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

std::string dds_loopback_config(uint32_t) {
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

Expected<std::unique_ptr<PointCloud2Reader>> PointCloud2Reader::create(const PointCloud2Options&) {
  return Error(Errc::kUnsupported,
               "dds: this build has no DDS (Cyclone DDS was not found when it was configured; "
               "install cyclonedds-dev for the target and rebuild): no PointCloud2 input");
}

PointCloud2Reader::~PointCloud2Reader() = default;

bool PointCloud2Reader::take_latest(const PointRegion&, PointCloud*, int64_t, int64_t*) {
  return false;
}

int PointCloud2Reader::publishers() const {
  return 0;
}

const char* PointCloud2Reader::type_name() {
  return "";
}

}  // namespace aprt
