// libFuzzer targets: arbitrary bytes as a LiDAR scan file through the scan
// reader, written with the extension APRT_FUZZ_EXT (".pcd": pcd_fuzz,
// ".bin": kitti_fuzz) so that the reader takes it for that format. It
// must refuse (with a reason) or read: never crash, read outside its buffer,
// overflow, or hand on a point that is not finite or outside the region.
#include <cmath>
#include <cstdint>
#include <cstdlib>

#include "drivers/input/lidar/scan_reader.h"
#include "tests/fuzz/fuzz_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static aprt::ScanReader* reader = aprt::ScanReader::create().value().release();
  static aprt::PointCloud* cloud = aprt::PointCloud::create(1 << 14).value().release();
  const char* path = aprt::fuzz::write_input(data, size, APRT_FUZZ_EXT);
  if (!path) return 0;
  const aprt::PointRegion region;
  if (aprt::Status s = reader->read(path, region, cloud); !s) {
    (void)s.error().message();
    return 0;
  }
  if (cloud->size() > cloud->capacity()) std::abort();
  for (size_t i = 0; i < cloud->size(); ++i) {
    const auto& p = cloud->points()[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) std::abort();
    if (p.x < region.x_min || p.x > region.x_max || p.z < region.z_min || p.z > region.z_max)
      std::abort();
  }
  return 0;
}
