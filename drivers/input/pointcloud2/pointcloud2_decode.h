// sensor_msgs/msg/PointCloud2 -> PointCloud (issue #5), independent of DDS so
// that it can be tested and fuzzed on bytes. Any point_step and field layout:
// x, y, z required (FLOAT32 or FLOAT64), intensity optional (any numeric
// type), other fields ignored; big-endian clouds are byte-swapped. A message
// whose sizes do not add up, or that lacks a coordinate, is refused whole
// with the reason (the caller counts and logs it and keeps its last good
// scan); the points of an accepted one pass the PointCloud gate (NaN/Inf
// dropped, absurd values clipped, the count bounded -- all counted). @rt:
// allocation-free.
#pragma once

#include <cstddef>
#include <cstdint>

#include "drivers/input/lidar/point_cloud.h"

namespace aprt {

// sensor_msgs/msg/PointField datatypes.
enum class PointFieldType : uint8_t {
  kInt8 = 1,
  kUint8 = 2,
  kInt16 = 3,
  kUint16 = 4,
  kInt32 = 5,
  kUint32 = 6,
  kFloat32 = 7,
  kFloat64 = 8,
};

struct PointFieldView {
  const char* name;
  uint32_t offset;
  uint8_t datatype;
  uint32_t count;
};

struct PointCloud2View {
  uint32_t height, width;
  const PointFieldView* fields;
  size_t n_fields;
  bool is_bigendian;
  uint32_t point_step, row_step;
  const uint8_t* data;
  size_t data_bytes;
};

// Why a message was refused, for counters.
enum class CloudRefusal : uint8_t {
  kNone = 0,
  kMissingField,  // no x, y or z
  kBadField,      // a coordinate that is not FLOAT32/FLOAT64, or a field outside the point
  kBadLayout,     // point_step 0, row_step < width * point_step, sizes overflow
  kSizeMismatch,  // data is not row_step * height bytes
  kCount,
};
const char* cloud_refusal_name(CloudRefusal r);

// Decodes `m` into `out` (cleared with `region` first). On refusal returns an
// error naming the problem and sets *why; `out` is then untouched, so the
// caller still has its last good scan. @rt
Status decode_pointcloud2(const PointCloud2View& m, const PointRegion& region, PointCloud* out,
                          CloudRefusal* why) noexcept;

}  // namespace aprt
