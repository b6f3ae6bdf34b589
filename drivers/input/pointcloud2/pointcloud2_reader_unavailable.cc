// Built instead of the DDS module's reader when Cyclone DDS is not found for
// the target: a PointCloud2 source is refused at start with the reason.
#include "drivers/input/pointcloud2/pointcloud2_reader.h"

namespace aprt {

Expected<std::unique_ptr<PointCloud2Reader>> PointCloud2Reader::create(const PointCloud2Options&) {
  return Error(Errc::kUnsupported,
               "dds: this build has no DDS (Cyclone DDS was not found when it was configured; "
               "install cyclonedds-dev for the target and rebuild): no PointCloud2 input");
}

}  // namespace aprt
