// `aprt run --record FILE.mcap`: what a drive was, as a ROS 2 bag in MCAP
// (drivers/codec/mcap_writer.h) -- the frames or scans as they entered
// (sensor_msgs/Image, sensor_msgs/PointCloud2), the poses published
// (geometry_msgs/PoseWithCovarianceStamped, as on DDS), the diagnostics
// (diagnostic_msgs/DiagnosticArray) and one timing record per pose
// (aprt_msgs/PoseTiming: the estimate, its flags and state, the stage times)
// -- so a drive recorded on the vehicle replays on the desk
// (`source.type: mcap`) and opens in `ros2 bag` and Foxglove.
//
// The loop's threads only copy into preallocated single-producer rings (the
// capture thread its frames, the publisher its poses and diagnostics) and
// never wait: a full ring drops that record and counts it -- the recording
// loses a frame, the drive never does. A thread of its own ("aprt-record",
// normal priority) serialises and writes. Everything is allocated at create().
#pragma once

#include <pthread.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "drivers/input/frame.h"
#include "runtime/base/expected.h"

namespace aprt {

class McapWriter;

struct RecorderOptions {
  std::string path;
  size_t max_frame_bytes = 0;  // the source's largest frame (or scan: points x 16)
  bool scans = false;          // LiDAR: PointCloud2 instead of Image
  int ring_frames = 16;        // frames that may wait for the writer (2..256)
  std::string frame_topic;     // default /aprt/image or /aprt/points
  std::string pose_topic = "/aprt/pose_with_covariance";
  std::string diagnostics_topic = "/diagnostics";
  std::string frame_id = "map";  // of the poses and diagnostics
};

// One pose as the publisher saw it.
struct RecordedPose {
  int64_t stamp_ns = 0;  // the pose's header stamp (the frame's, wall clock)
  uint64_t index = 0;
  uint64_t frame_sequence = 0;
  uint32_t flags = 0;
  uint8_t state = 0;       // RunState
  bool published = false;  // went out as valid (DDS would have sent it)
  double position[3] = {}, orientation[4] = {1, 0, 0, 0}, covariance[36] = {};  // as published
  double estimate_position[3] = {}, estimate_orientation[4] = {1, 0, 0, 0};     // the model's
  int64_t capture_ns = 0, inference_start_ns = 0, inference_end_ns = 0, publish_ns = 0;
};

struct RecorderStats {
  uint64_t frames = 0, poses = 0, statuses = 0;
  uint64_t frames_dropped = 0, poses_dropped = 0, statuses_dropped = 0;  // ring full
  uint64_t write_errors = 0;
  uint64_t bytes = 0;
};

class Recorder {
 public:
  static Expected<std::unique_ptr<Recorder>> create(const RecorderOptions& o);
  ~Recorder();  // stop(), if not done
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  // Real-time side: copy and return, never wait. @rt
  void offer_frame(const FrameBuffer& f, int64_t stamp_ns) noexcept;  // the capture thread
  void offer_pose(const RecordedPose& p) noexcept;                    // the publisher thread
  void offer_status(int64_t stamp_ns, uint8_t level, const char* message, const char* const* keys,
                    const char* const* values, int count) noexcept;  // the publisher thread

  // Drains what is queued, writes the summary, closes the file. The status
  // of the close (a full disk shows here and in the counts).
  Status stop();
  RecorderStats stats() const;
  const std::string& path() const { return o_.path; }

 private:
  Recorder() = default;
  void run() noexcept;
  bool drain() noexcept;  // true when it wrote something

  RecorderOptions o_;
  std::unique_ptr<McapWriter> writer_;
  uint16_t ch_frame_ = 0, ch_pose_ = 0, ch_diag_ = 0, ch_timing_ = 0;
  struct Rings;
  std::unique_ptr<Rings> rings_;
  std::unique_ptr<uint8_t[]> cdr_;  // one serialised message
  size_t cdr_cap_ = 0;
  pthread_t thread_{};
  bool started_ = false;
  std::atomic<bool> stop_{false};
  bool stopped_ = false;
  Status close_status_;
};

// "record: FILE: 240 frames, 240 poses, 12 diagnostics, 23.1 MB (dropped: ...)".
void recorder_summary(const Recorder& r, char* buf, size_t size);

}  // namespace aprt
