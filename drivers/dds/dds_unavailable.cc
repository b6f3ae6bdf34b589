// Built instead of dds_domain.cc and dds_listener.cc when Cyclone DDS is not
// found for the target.
#include "drivers/dds/dds_domain.h"
#include "drivers/dds/dds_listener.h"

namespace aprt {

std::string dds_loopback_config(uint32_t) {
  return "";
}

std::string ros_topic(const std::string& ros_name) {
  return "rt" + ros_name;
}

Error dds_failure(const char* what, int32_t) {
  return Error(Errc::kUnsupported, "dds: %s: this build has no DDS", what);
}

Expected<int32_t> dds_join(uint32_t, bool, int32_t* domain_handle) {
  *domain_handle = 0;
  return dds_failure("join", 0);
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
