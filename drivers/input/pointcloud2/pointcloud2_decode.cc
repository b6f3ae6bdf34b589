#include "drivers/input/pointcloud2/pointcloud2_decode.h"

#include <cstdarg>
#include <cstdio>
#include <cstring>

#include "runtime/base/check.h"

namespace aprt {
namespace {

size_t type_bytes(uint8_t t) {
  switch (PointFieldType(t)) {
    case PointFieldType::kInt8:
    case PointFieldType::kUint8: return 1;
    case PointFieldType::kInt16:
    case PointFieldType::kUint16: return 2;
    case PointFieldType::kInt32:
    case PointFieldType::kUint32:
    case PointFieldType::kFloat32: return 4;
    case PointFieldType::kFloat64: return 8;
  }
  return 0;
}

struct Field {
  uint32_t offset = 0;
  uint8_t type = 0;
  bool present = false;
};

// One value of type `t` at p, in the message's byte order, as float.
float read_value(const uint8_t* p, uint8_t t, bool swap) {
  uint8_t b[8];
  const size_t n = type_bytes(t);
  for (size_t i = 0; i < n; ++i) b[i] = swap ? p[n - 1 - i] : p[i];
  switch (PointFieldType(t)) {
    case PointFieldType::kInt8: return float(int8_t(b[0]));
    case PointFieldType::kUint8: return float(b[0]);
    case PointFieldType::kInt16: {
      int16_t v;
      std::memcpy(&v, b, 2);
      return float(v);
    }
    case PointFieldType::kUint16: {
      uint16_t v;
      std::memcpy(&v, b, 2);
      return float(v);
    }
    case PointFieldType::kInt32: {
      int32_t v;
      std::memcpy(&v, b, 4);
      return float(v);
    }
    case PointFieldType::kUint32: {
      uint32_t v;
      std::memcpy(&v, b, 4);
      return float(v);
    }
    case PointFieldType::kFloat32: {
      float v;
      std::memcpy(&v, b, 4);
      return v;
    }
    case PointFieldType::kFloat64: {
      double v;
      std::memcpy(&v, b, 8);
      return float(v);
    }
  }
  return 0.0f;
}

Error refuse(CloudRefusal r, CloudRefusal* why, const char* fmt, ...)
    __attribute__((format(printf, 3, 4)));
Error refuse(CloudRefusal r, CloudRefusal* why, const char* fmt, ...) {
  *why = r;
  char msg[200];
  va_list ap;
  va_start(ap, fmt);
  std::vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  return Error(Errc::kInvalidArgument, "PointCloud2: %s", msg);
}

}  // namespace

const char* cloud_refusal_name(CloudRefusal r) {
  switch (r) {
    case CloudRefusal::kNone: return "none";
    case CloudRefusal::kMissingField: return "missing-field";
    case CloudRefusal::kBadField: return "bad-field";
    case CloudRefusal::kBadLayout: return "bad-layout";
    case CloudRefusal::kSizeMismatch: return "size-mismatch";
    case CloudRefusal::kCount: break;
  }
  return "?";
}

Status decode_pointcloud2(const PointCloud2View& m, const PointRegion& region, PointCloud* out,
                          CloudRefusal* why) noexcept {
  *why = CloudRefusal::kNone;
  Field f[4];  // x, y, z, intensity
  static const char* const kNames[4] = {"x", "y", "z", "intensity"};
  for (size_t i = 0; i < m.n_fields; ++i) {
    const PointFieldView& pf = m.fields[i];
    if (!pf.name) continue;
    for (int k = 0; k < 4; ++k) {
      if (f[k].present || std::strcmp(pf.name, kNames[k]) != 0) continue;
      const size_t bytes = type_bytes(pf.datatype);
      if (bytes == 0) {
        return refuse(CloudRefusal::kBadField, why, "field '%s' has unknown datatype %u", kNames[k],
                      unsigned(pf.datatype));
      }
      if (k < 3 && PointFieldType(pf.datatype) != PointFieldType::kFloat32 &&
          PointFieldType(pf.datatype) != PointFieldType::kFloat64) {
        return refuse(CloudRefusal::kBadField, why,
                      "field '%s' is of datatype %u; coordinates must be FLOAT32 or FLOAT64",
                      kNames[k], unsigned(pf.datatype));
      }
      if (pf.count < 1 || uint64_t(pf.offset) + bytes > m.point_step) {
        return refuse(CloudRefusal::kBadField, why,
                      "field '%s' (offset %u, %zu bytes, count %u) does not fit a %u-byte point",
                      kNames[k], pf.offset, bytes, pf.count, m.point_step);
      }
      f[k] = {pf.offset, pf.datatype, true};
    }
  }
  for (int k = 0; k < 3; ++k) {
    if (!f[k].present) {
      return refuse(CloudRefusal::kMissingField, why, "no '%s' field", kNames[k]);
    }
  }
  if (m.point_step == 0 || uint64_t(m.width) * m.point_step > m.row_step) {
    return refuse(CloudRefusal::kBadLayout, why, "point_step %u, row_step %u for width %u",
                  m.point_step, m.row_step, m.width);
  }
  const uint64_t need = uint64_t(m.row_step) * m.height;
  if (need != m.data_bytes) {
    return refuse(CloudRefusal::kSizeMismatch, why,
                  "data has %zu bytes; height %u x row_step %u needs %llu", m.data_bytes, m.height,
                  m.row_step, static_cast<unsigned long long>(need));
  }
  out->clear(region);  // only now: a refused message leaves `out` as it was
  const bool swap = m.is_bigendian;
  for (uint32_t r = 0; r < m.height; ++r) {
    const uint8_t* row = m.data + size_t(r) * m.row_step;
    for (uint32_t c = 0; c < m.width; ++c) {
      const uint8_t* p = row + size_t(c) * m.point_step;
      const float x = read_value(p + f[0].offset, f[0].type, swap);
      const float y = read_value(p + f[1].offset, f[1].type, swap);
      const float z = read_value(p + f[2].offset, f[2].type, swap);
      const float in = f[3].present ? read_value(p + f[3].offset, f[3].type, swap) : 0.0f;
      out->add(x, y, z, in);
    }
  }
  return ok();
}

}  // namespace aprt
