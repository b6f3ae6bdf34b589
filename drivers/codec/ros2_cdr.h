// ROS 2 messages as CDR bytes (XCDR1, little endian, with the 4-byte
// encapsulation header: what ROS 2 puts on the wire and in a bag), written
// into a caller's buffer -- no allocation -- and the message definitions
// (ros2msg text with dependencies, as `ros2 bag` stores them in MCAP
// schemas). For recording (MCAP) what aprt publishes on DDS and what entered
// it: the DDS path itself serialises through Cyclone (config/idl).
#pragma once

#include <cstddef>
#include <cstdint>

namespace aprt::ros2 {

// Writes CDR into [buf, buf + cap); alignment counts from after the header.
class CdrWriter {
 public:
  CdrWriter(uint8_t* buf, size_t cap) noexcept;
  void u8(uint8_t v) noexcept { put(&v, 1, 1); }
  void u32(uint32_t v) noexcept { put(&v, 4, 4); }
  void i32(int32_t v) noexcept { put(&v, 4, 4); }
  void f64(double v) noexcept { put(&v, 8, 8); }
  void u64(uint64_t v) noexcept { put(&v, 8, 8); }
  void i64(int64_t v) noexcept { put(&v, 8, 8); }
  void str(const char* s) noexcept;              // u32 length with the NUL, the bytes, the NUL
  void bytes(const void* p, size_t n) noexcept;  // uint8[]: u32 count, the bytes
  void stamp(int64_t unix_ns) noexcept;          // builtin_interfaces/Time
  void header(int64_t unix_ns, const char* frame_id) noexcept {
    stamp(unix_ns);
    str(frame_id);
  }
  // Bytes written, or 0 when they did not fit.
  size_t size() const noexcept { return ok_ ? pos_ : 0; }

 private:
  void put(const void* p, size_t n, size_t align) noexcept;
  uint8_t* buf_;
  size_t cap_, pos_ = 0;
  bool ok_ = true;
};

// sensor_msgs/msg/Image; `encoding` one of ROS's names ("rgb8", "bgr8",
// "yuv422_yuy2", "yuv422" (UYVY), "nv12").
size_t image(uint8_t* buf, size_t cap, int64_t stamp_ns, const char* frame_id, uint32_t width,
             uint32_t height, const char* encoding, uint32_t step, const void* data,
             size_t size) noexcept;
// sensor_msgs/msg/PointCloud2 of `n` points x y z intensity (float32, 16 bytes each).
size_t pointcloud2_xyzi(uint8_t* buf, size_t cap, int64_t stamp_ns, const char* frame_id,
                        const float* xyzi, uint32_t n) noexcept;
// geometry_msgs/msg/PoseWithCovarianceStamped; orientation w x y z.
size_t pose_with_covariance(uint8_t* buf, size_t cap, int64_t stamp_ns, const char* frame_id,
                            const double position[3], const double orientation[4],
                            const double covariance[36]) noexcept;
// diagnostic_msgs/msg/DiagnosticArray with one status.
size_t diagnostics(uint8_t* buf, size_t cap, int64_t stamp_ns, const char* frame_id, uint8_t level,
                   const char* name, const char* message, const char* hardware_id,
                   const char* const* keys, const char* const* values, int count) noexcept;

// aprt_msgs/msg/PoseTiming: one per pose -- the model's estimate, its flags
// and run state, whether it went out as valid, the stage times (CLOCK_MONOTONIC ns).
struct PoseTiming {
  int64_t stamp_ns;
  uint64_t index, frame_sequence;
  uint32_t flags;
  uint8_t state;
  bool published;
  double position[3], orientation[4];  // the estimate; orientation w x y z
  int64_t capture_ns, inference_start_ns, inference_end_ns, publish_ns;
};
size_t pose_timing(uint8_t* buf, size_t cap, const char* frame_id, const PoseTiming& t) noexcept;

// Reading (what `source.type: mcap` replays): views into the CDR bytes,
// bounds-checked; false when the bytes are not such a message (little-endian
// CDR only: what ROS 2 writes on little-endian machines).
struct ImageMsg {
  int64_t stamp_ns;
  const char* frame_id;
  const char* encoding;
  uint32_t height, width, step;
  bool is_bigendian;
  const uint8_t* data;
  size_t size;
};
bool read_image(const uint8_t* cdr, size_t n, ImageMsg* out) noexcept;

struct PointFieldMsg {
  const char* name;
  uint32_t offset;
  uint8_t datatype;
  uint32_t count;
};
struct PointCloud2Msg {
  static constexpr int kMaxFields = 16;
  int64_t stamp_ns;
  const char* frame_id;
  uint32_t height, width;
  PointFieldMsg fields[kMaxFields];
  int n_fields;
  bool is_bigendian;
  uint32_t point_step, row_step;
  const uint8_t* data;
  size_t size;
  bool is_dense;
};
bool read_pointcloud2(const uint8_t* cdr, size_t n, PointCloud2Msg* out) noexcept;

// The definitions, ros2msg text with every nested type appended (the
// "=====" separated MSG: sections of rosbag2's MCAP storage).
extern const char kImageDefinition[];
extern const char kPointCloud2Definition[];
extern const char kPoseWithCovarianceStampedDefinition[];
extern const char kDiagnosticArrayDefinition[];
extern const char kPoseTimingDefinition[];

}  // namespace aprt::ros2
