// Built instead of the DDS module's reader when Cyclone DDS is not found for
// the target: a DDS odometry input is refused at start with the reason.
#include "drivers/input/twist/twist_reader.h"

namespace aprt {

Expected<std::unique_ptr<TwistReader>> TwistReader::create(const TwistOptions&) {
  return Error(Errc::kUnsupported,
               "dds: this build has no DDS (Cyclone DDS was not found when it was configured; "
               "install cyclonedds-dev for the target and rebuild): no odometry input over DDS");
}

}  // namespace aprt
