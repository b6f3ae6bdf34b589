// PointCloud2Reader::create() in the program: the reader is made by the DDS
// module (drivers/dds/dds_module.h).
#include "drivers/dds/dds_module.h"
#include "drivers/input/pointcloud2/pointcloud2_reader.h"

namespace aprt {

Expected<std::unique_ptr<PointCloud2Reader>> PointCloud2Reader::create(
    const PointCloud2Options& o) {
  auto m = open_dds_module();
  if (!m) return m.error();
  return m.value()->create_pointcloud2_reader(o);
}

}  // namespace aprt
