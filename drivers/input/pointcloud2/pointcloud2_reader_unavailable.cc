// Built instead of pointcloud2_reader.cc when Cyclone DDS is not found for
// the target: a PointCloud2 source is refused at start with the reason.
#include "drivers/input/pointcloud2/pointcloud2_reader.h"

namespace aprt {

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
