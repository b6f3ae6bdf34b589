#include "drivers/codec/ros2_cdr.h"

#include <cstring>

namespace aprt::ros2 {

CdrWriter::CdrWriter(uint8_t* buf, size_t cap) noexcept : buf_(buf), cap_(cap) {
  static const uint8_t kCdrLe[4] = {0x00, 0x01, 0x00, 0x00};  // CDR, little endian, no options
  if (cap_ < 4) {
    ok_ = false;
    return;
  }
  std::memcpy(buf_, kCdrLe, 4);
  pos_ = 4;
}

void CdrWriter::put(const void* p, size_t n, size_t align) noexcept {
  if (!ok_) return;
  const size_t body = pos_ - 4;  // alignment is relative to the end of the header
  const size_t pad = (align - body % align) % align;
  if (pos_ + pad + n > cap_) {
    ok_ = false;
    return;
  }
  std::memset(buf_ + pos_, 0, pad);
  pos_ += pad;
  std::memcpy(buf_ + pos_, p, n);
  pos_ += n;
}

void CdrWriter::str(const char* s) noexcept {
  const size_t n = std::strlen(s);
  u32(uint32_t(n + 1));
  put(s, n + 1, 1);
}

void CdrWriter::bytes(const void* p, size_t n) noexcept {
  u32(uint32_t(n));
  put(p, n, 1);
}

void CdrWriter::stamp(int64_t ns) noexcept {
  int64_t sec = ns / 1000000000, nsec = ns % 1000000000;
  if (nsec < 0) {
    nsec += 1000000000;
    --sec;
  }
  i32(int32_t(sec));
  u32(uint32_t(nsec));
}

size_t image(uint8_t* buf, size_t cap, int64_t stamp_ns, const char* frame_id, uint32_t width,
             uint32_t height, const char* encoding, uint32_t step, const void* data,
             size_t size) noexcept {
  CdrWriter w(buf, cap);
  w.header(stamp_ns, frame_id);
  w.u32(height);
  w.u32(width);
  w.str(encoding);
  w.u8(0);  // is_bigendian
  w.u32(step);
  w.bytes(data, size);
  return w.size();
}

size_t pointcloud2_xyzi(uint8_t* buf, size_t cap, int64_t stamp_ns, const char* frame_id,
                        const float* xyzi, uint32_t n) noexcept {
  CdrWriter w(buf, cap);
  w.header(stamp_ns, frame_id);
  w.u32(1);  // height: unordered
  w.u32(n);  // width
  static const char* const kNames[4] = {"x", "y", "z", "intensity"};
  w.u32(4);
  for (uint32_t k = 0; k < 4; ++k) {
    w.str(kNames[k]);
    w.u32(4 * k);  // offset
    w.u8(7);       // FLOAT32
    w.u32(1);      // count
  }
  w.u8(0);  // is_bigendian
  w.u32(16);
  w.u32(16 * n);
  w.bytes(xyzi, size_t(n) * 16);
  w.u8(1);  // is_dense
  return w.size();
}

size_t pose_with_covariance(uint8_t* buf, size_t cap, int64_t stamp_ns, const char* frame_id,
                            const double position[3], const double orientation[4],
                            const double covariance[36]) noexcept {
  CdrWriter w(buf, cap);
  w.header(stamp_ns, frame_id);
  for (int k = 0; k < 3; ++k) w.f64(position[k]);
  w.f64(orientation[1]);  // ROS order: x y z w
  w.f64(orientation[2]);
  w.f64(orientation[3]);
  w.f64(orientation[0]);
  for (int k = 0; k < 36; ++k) w.f64(covariance[k]);
  return w.size();
}

size_t diagnostics(uint8_t* buf, size_t cap, int64_t stamp_ns, const char* frame_id, uint8_t level,
                   const char* name, const char* message, const char* hardware_id,
                   const char* const* keys, const char* const* values, int count) noexcept {
  CdrWriter w(buf, cap);
  w.header(stamp_ns, frame_id);
  w.u32(1);  // one status
  w.u8(level);
  w.str(name);
  w.str(message);
  w.str(hardware_id);
  w.u32(uint32_t(count));
  for (int i = 0; i < count; ++i) {
    w.str(keys[i]);
    w.str(values[i]);
  }
  return w.size();
}

size_t pose_timing(uint8_t* buf, size_t cap, const char* frame_id, const PoseTiming& t) noexcept {
  CdrWriter w(buf, cap);
  w.header(t.stamp_ns, frame_id);
  w.u64(t.index);
  w.u64(t.frame_sequence);
  w.u32(t.flags);
  w.u8(t.state);
  w.u8(t.published ? 1 : 0);
  for (int k = 0; k < 3; ++k) w.f64(t.position[k]);
  for (int k = 0; k < 4; ++k) w.f64(t.orientation[k]);
  w.i64(t.capture_ns);
  w.i64(t.inference_start_ns);
  w.i64(t.inference_end_ns);
  w.i64(t.publish_ns);
  return w.size();
}

namespace {

class CdrReader {
 public:
  CdrReader(const uint8_t* p, size_t n) : p_(p), n_(n) {
    ok_ = n >= 4 && p[0] == 0x00 && p[1] == 0x01;  // CDR, little endian
    pos_ = 4;
  }
  bool ok() const { return ok_; }
  template <typename T>
  T get() {
    T v{};
    align(sizeof(T));
    if (!ok_ || pos_ + sizeof v > n_) {
      ok_ = false;
      return v;
    }
    std::memcpy(&v, p_ + pos_, sizeof v);
    pos_ += sizeof v;
    return v;
  }
  // A string: its bytes end in a NUL inside the message, or the read fails.
  const char* str() {
    const uint32_t len = get<uint32_t>();
    if (!ok_ || len == 0 || pos_ + len > n_ || p_[pos_ + len - 1] != 0) {
      ok_ = false;
      return "";
    }
    const char* s = reinterpret_cast<const char*>(p_ + pos_);
    pos_ += len;
    return s;
  }
  const uint8_t* bytes(size_t* size) {
    const uint32_t len = get<uint32_t>();
    if (!ok_ || pos_ + len > n_) {
      ok_ = false;
      *size = 0;
      return nullptr;
    }
    const uint8_t* b = p_ + pos_;
    pos_ += len;
    *size = len;
    return b;
  }
  int64_t stamp() {
    const int32_t sec = get<int32_t>();
    const uint32_t nsec = get<uint32_t>();
    if (nsec >= 1000000000u) ok_ = false;
    return int64_t(sec) * 1000000000 + nsec;
  }

 private:
  void align(size_t a) {
    const size_t body = pos_ - 4;
    pos_ += (a - body % a) % a;
  }
  const uint8_t* p_;
  size_t n_, pos_ = 0;
  bool ok_ = false;
};

}  // namespace

bool read_image(const uint8_t* cdr, size_t n, ImageMsg* out) noexcept {
  CdrReader r(cdr, n);
  out->stamp_ns = r.stamp();
  out->frame_id = r.str();
  out->height = r.get<uint32_t>();
  out->width = r.get<uint32_t>();
  out->encoding = r.str();
  out->is_bigendian = r.get<uint8_t>() != 0;
  out->step = r.get<uint32_t>();
  out->data = r.bytes(&out->size);
  return r.ok();
}

bool read_pointcloud2(const uint8_t* cdr, size_t n, PointCloud2Msg* out) noexcept {
  CdrReader r(cdr, n);
  out->stamp_ns = r.stamp();
  out->frame_id = r.str();
  out->height = r.get<uint32_t>();
  out->width = r.get<uint32_t>();
  const uint32_t fields = r.get<uint32_t>();
  if (fields > uint32_t(PointCloud2Msg::kMaxFields)) return false;
  out->n_fields = int(fields);
  for (uint32_t i = 0; i < fields; ++i) {
    PointFieldMsg& f = out->fields[i];
    f.name = r.str();
    f.offset = r.get<uint32_t>();
    f.datatype = r.get<uint8_t>();
    f.count = r.get<uint32_t>();
  }
  out->is_bigendian = r.get<uint8_t>() != 0;
  out->point_step = r.get<uint32_t>();
  out->row_step = r.get<uint32_t>();
  out->data = r.bytes(&out->size);
  out->is_dense = r.get<uint8_t>() != 0;
  return r.ok();
}

#define APRT_SEP \
  "================================================================================\n"
#define APRT_HEADER_DEPS            \
  APRT_SEP                          \
  "MSG: std_msgs/Header\n"          \
  "builtin_interfaces/Time stamp\n" \
  "string frame_id\n" APRT_SEP      \
  "MSG: builtin_interfaces/Time\n"  \
  "int32 sec\n"                     \
  "uint32 nanosec\n"

const char kImageDefinition[] =
    "std_msgs/Header header\n"
    "uint32 height\n"
    "uint32 width\n"
    "string encoding\n"
    "uint8 is_bigendian\n"
    "uint32 step\n"
    "uint8[] data\n" APRT_HEADER_DEPS;

const char kPointCloud2Definition[] =
    "std_msgs/Header header\n"
    "uint32 height\n"
    "uint32 width\n"
    "PointField[] fields\n"
    "bool is_bigendian\n"
    "uint32 point_step\n"
    "uint32 row_step\n"
    "uint8[] data\n"
    "bool is_dense\n" APRT_HEADER_DEPS APRT_SEP
    "MSG: sensor_msgs/PointField\n"
    "uint8 INT8 = 1\n"
    "uint8 UINT8 = 2\n"
    "uint8 INT16 = 3\n"
    "uint8 UINT16 = 4\n"
    "uint8 INT32 = 5\n"
    "uint8 UINT32 = 6\n"
    "uint8 FLOAT32 = 7\n"
    "uint8 FLOAT64 = 8\n"
    "string name\n"
    "uint32 offset\n"
    "uint8 datatype\n"
    "uint32 count\n";

const char kPoseWithCovarianceStampedDefinition[] =
    "std_msgs/Header header\n"
    "PoseWithCovariance pose\n" APRT_HEADER_DEPS APRT_SEP
    "MSG: geometry_msgs/PoseWithCovariance\n"
    "Pose pose\n"
    "float64[36] covariance\n" APRT_SEP
    "MSG: geometry_msgs/Pose\n"
    "Point position\n"
    "Quaternion orientation\n" APRT_SEP
    "MSG: geometry_msgs/Point\n"
    "float64 x\n"
    "float64 y\n"
    "float64 z\n" APRT_SEP
    "MSG: geometry_msgs/Quaternion\n"
    "float64 x 0\n"
    "float64 y 0\n"
    "float64 z 0\n"
    "float64 w 1\n";

const char kDiagnosticArrayDefinition[] =
    "std_msgs/Header header\n"
    "DiagnosticStatus[] status\n" APRT_HEADER_DEPS APRT_SEP
    "MSG: diagnostic_msgs/DiagnosticStatus\n"
    "byte OK=0\n"
    "byte WARN=1\n"
    "byte ERROR=2\n"
    "byte STALE=3\n"
    "byte level\n"
    "string name\n"
    "string message\n"
    "string hardware_id\n"
    "KeyValue[] values\n" APRT_SEP
    "MSG: diagnostic_msgs/KeyValue\n"
    "string key\n"
    "string value\n";

const char kPoseTimingDefinition[] =
    "# aprt's record of one pose (docs/outputs.md, \"Recording\")\n"
    "std_msgs/Header header\n"
    "uint64 index\n"
    "uint64 frame_sequence\n"
    "uint32 flags\n"
    "uint8 state\n"
    "bool published\n"
    "float64[3] position\n"
    "float64[4] orientation\n"
    "int64 capture_ns\n"
    "int64 inference_start_ns\n"
    "int64 inference_end_ns\n"
    "int64 publish_ns\n" APRT_HEADER_DEPS;

#undef APRT_HEADER_DEPS
#undef APRT_SEP

}  // namespace aprt::ros2
