// libFuzzer target: arbitrary bytes as a sensor_msgs/msg/PointCloud2 (the
// header fields, up to 8 field descriptions, the data) through the decoder.
// It must refuse or decode -- never read outside the data, never crash -- and
// a decoded cloud never holds more points than the buffer or a NaN.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>

#include "drivers/input/pointcloud2/pointcloud2_decode.h"

namespace {

template <class T>
T take(const uint8_t*& p, size_t& n) {
  T v{};
  const size_t k = n < sizeof v ? n : sizeof v;
  std::memcpy(&v, p, k);
  p += k;
  n -= k;
  return v;
}

aprt::PointCloud* cloud() {
  static aprt::PointCloud* c = aprt::PointCloud::create(4096).value().release();
  return c;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const uint8_t* p = data;
  size_t n = size;
  static const char* const kNames[] = {"x", "y", "z", "intensity", "ring", "t", "", "x"};
  aprt::PointFieldView fields[8];
  const size_t nf = take<uint8_t>(p, n) % 9;
  for (size_t i = 0; i < nf; ++i) {
    fields[i].name = kNames[take<uint8_t>(p, n) % 8];
    fields[i].offset = take<uint16_t>(p, n);
    fields[i].datatype = take<uint8_t>(p, n);
    fields[i].count = take<uint8_t>(p, n);
  }
  aprt::PointCloud2View v{};
  v.height = take<uint16_t>(p, n);
  v.width = take<uint16_t>(p, n);
  v.is_bigendian = take<uint8_t>(p, n) & 1;
  v.point_step = take<uint16_t>(p, n);
  v.row_step = take<uint32_t>(p, n);
  v.fields = fields;
  v.n_fields = nf;
  // The data in a buffer of exactly its size, so that ASan sees any overrun.
  uint8_t* copy = static_cast<uint8_t*>(std::malloc(n ? n : 1));
  std::memcpy(copy, p, n);
  v.data = copy;
  v.data_bytes = n;
  aprt::CloudRefusal why;
  if (aprt::decode_pointcloud2(v, aprt::PointRegion{}, cloud(), &why)) {
    if (cloud()->size() > cloud()->capacity()) std::abort();
    for (size_t i = 0; i < cloud()->size(); ++i) {
      const auto& q = cloud()->points()[i];
      if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z)) std::abort();
    }
  }
  std::free(copy);
  return 0;
}
