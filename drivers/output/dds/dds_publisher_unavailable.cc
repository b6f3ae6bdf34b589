// Built instead of dds_loader.cc when Cyclone DDS is not found for the
// target: DDS output then fails at start with a reason, like any other
// unavailable output, and the rest of aprt runs.
#include "drivers/output/dds/dds_listener.h"
#include "drivers/output/dds/dds_publisher.h"

namespace aprt {

Expected<std::unique_ptr<DdsPublisher>> DdsPublisher::create(const DdsOptions&) {
  return Error(Errc::kUnsupported,
               "dds: this build has no DDS (Cyclone DDS was not found when it was configured; "
               "install cyclonedds-dev for the target and rebuild)");
}

Expected<std::unique_ptr<DdsListener>> DdsListener::create(const DdsOptions&) {
  return Error(Errc::kUnsupported,
               "dds: this build has no DDS (Cyclone DDS was not found when it was configured)");
}

}  // namespace aprt
