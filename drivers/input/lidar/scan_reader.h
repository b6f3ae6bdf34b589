// LiDAR scans from files, for replay (issue #5): KITTI `.bin` (x y z
// intensity as float32, little-endian, no header) and PCD v0.7 (`DATA ascii`
// or `DATA binary`; fields x, y, z required, intensity optional, in any order
// and with any other fields beside them; x/y/z as F 4 or F 8, intensity as F
// 4/8 or U/I 1/2/4). Read through one fixed I/O buffer into a PointCloud (its
// gate drops NaN/Inf, clips, bounds the count): no allocation per scan.
// A file whose size disagrees with its own header, or a PCD without x/y/z,
// is refused with the reason; binary_compressed PCD is refused by name.
#pragma once

#include <memory>

#include "drivers/input/lidar/point_cloud.h"
#include "runtime/base/file_io.h"

namespace aprt {

class ScanReader {
 public:
  static Expected<std::unique_ptr<ScanReader>> create();
  ~ScanReader();

  // A scan file is at most this large (16 M points of 16 bytes).
  static constexpr uint64_t kMaxScanBytes = uint64_t(256) << 20;
  // .bin or .pcd by the file's extension; a regular file (a FIFO or a device
  // is refused) of at most kMaxScanBytes.
  Status read(const char* path, const PointRegion& region, PointCloud* out);

 private:
  ScanReader() = default;
  Status read_kitti(const InputFile& file, const char* path, PointCloud* out);
  Status read_pcd(const InputFile& file, const char* path, PointCloud* out);
  static constexpr size_t kBuffer = 1 << 16;
  static constexpr long kMaxCount = 1024;        // values per PCD field
  static constexpr long kMaxPoints = 100000000;  // PCD POINTS
  char* buf_ = nullptr;
};

}  // namespace aprt
