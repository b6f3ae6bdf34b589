#include "runtime/loop/recorder.h"

#include <pthread.h>
#include <time.h>

#include <cstdio>
#include <cstring>
#include <new>

#include "drivers/codec/mcap_writer.h"
#include "drivers/codec/ros2_cdr.h"
#include "runtime/loop/spsc_ring.h"

namespace aprt {
namespace {

const char* ros_encoding(PixelFormat f) {
  switch (f) {
    case PixelFormat::kRgb24: return "rgb8";
    case PixelFormat::kBgr24: return "bgr8";
    case PixelFormat::kYuyv: return "yuv422_yuy2";
    case PixelFormat::kUyvy: return "yuv422";  // ROS's name for UYVY
    case PixelFormat::kNv12: return "nv12";
    case PixelFormat::kGray8: return "mono8";
  }
  return "rgb8";
}

}  // namespace

struct Recorder::Rings {
  // Frames: slots with their own storage (sized at run time, so not a
  // SpscRing, whose items live inside it), handed over by index.
  struct Frame {
    FrameInfo info;
    int64_t stamp_ns = 0;
    std::unique_ptr<uint8_t[]> data;
  };
  std::unique_ptr<Frame[]> frames;
  size_t frame_slots = 0;
  alignas(64) std::atomic<uint64_t> frame_head{0};
  alignas(64) std::atomic<uint64_t> frame_tail{0};

  SpscRing<RecordedPose, 256> poses;

  struct Status {
    static constexpr int kMax = 28;
    int64_t stamp_ns = 0;
    uint8_t level = 0;
    int count = 0;
    char message[128] = {};
    char keys[kMax][32] = {};
    char values[kMax][96] = {};  // the longest reason fits
  };
  SpscRing<Status, 16> statuses;
  Status status_in, status_out;  // the publisher's and the writer's copy (no 2 KiB on a stack)

  std::atomic<uint64_t> frames_dropped{0}, poses_dropped{0}, statuses_dropped{0};
  std::atomic<uint64_t> frames_written{0}, poses_written{0}, timings_written{0};
  std::atomic<uint64_t> statuses_written{0}, write_errors{0};
  std::atomic<uint64_t> bytes{0};
};

Expected<std::unique_ptr<Recorder>> Recorder::create(const RecorderOptions& o) {
  if (o.ring_frames < 2 || o.ring_frames > 256) {
    return Error(Errc::kInvalidArgument, "record: ring_frames %d: 2..256", o.ring_frames);
  }
  std::unique_ptr<Recorder> r(new (std::nothrow) Recorder());
  if (!r) return Error(Errc::kOutOfMemory, "record: out of memory");
  r->o_ = o;
  if (r->o_.frame_topic.empty()) r->o_.frame_topic = o.scans ? "/aprt/points" : "/aprt/image";
  r->rings_.reset(new (std::nothrow) Rings());
  if (!r->rings_) return Error(Errc::kOutOfMemory, "record: out of memory");
  Rings& g = *r->rings_;
  g.frame_slots = size_t(o.ring_frames);
  g.frames.reset(new (std::nothrow) Rings::Frame[g.frame_slots]);
  if (!g.frames) return Error(Errc::kOutOfMemory, "record: out of memory");
  for (size_t i = 0; i < g.frame_slots; ++i) {
    g.frames[i].data.reset(new (std::nothrow) uint8_t[o.max_frame_bytes]);
    if (!g.frames[i].data) {
      return Error(Errc::kOutOfMemory, "record: out of memory for %d frames of %zu bytes",
                   o.ring_frames, o.max_frame_bytes);
    }
    std::memset(g.frames[i].data.get(), 0, o.max_frame_bytes);  // resident now, not mid-drive
  }
  r->cdr_cap_ = o.max_frame_bytes + 4096;
  r->cdr_.reset(new (std::nothrow) uint8_t[r->cdr_cap_]);
  if (!r->cdr_) return Error(Errc::kOutOfMemory, "record: out of memory");

  auto w = McapWriter::create(o.path.c_str(), "aprt");
  if (!w) return Error(w.error().code(), "record: %s", w.error().message());
  r->writer_ = std::move(w.value());
  McapWriter& m = *r->writer_;
  auto frame_schema =
      o.scans ? m.add_schema("sensor_msgs/msg/PointCloud2", "ros2msg", ros2::kPointCloud2Definition)
              : m.add_schema("sensor_msgs/msg/Image", "ros2msg", ros2::kImageDefinition);
  auto pose_schema = m.add_schema("geometry_msgs/msg/PoseWithCovarianceStamped", "ros2msg",
                                  ros2::kPoseWithCovarianceStampedDefinition);
  auto diag_schema = m.add_schema("diagnostic_msgs/msg/DiagnosticArray", "ros2msg",
                                  ros2::kDiagnosticArrayDefinition);
  auto timing_schema =
      m.add_schema("aprt_msgs/msg/PoseTiming", "ros2msg", ros2::kPoseTimingDefinition);
  if (!frame_schema || !pose_schema || !diag_schema || !timing_schema) {
    return Error(Errc::kIo, "record: %s: cannot write the schemas", o.path.c_str());
  }
  auto cf = m.add_channel(frame_schema.value(), r->o_.frame_topic.c_str(), "cdr");
  auto cp = m.add_channel(pose_schema.value(), o.pose_topic.c_str(), "cdr");
  auto cd = m.add_channel(diag_schema.value(), o.diagnostics_topic.c_str(), "cdr");
  auto ct = m.add_channel(timing_schema.value(), "/aprt/pose_timing", "cdr");
  if (!cf || !cp || !cd || !ct) {
    return Error(Errc::kIo, "record: %s: cannot write the channels", o.path.c_str());
  }
  r->ch_frame_ = cf.value();
  r->ch_pose_ = cp.value();
  r->ch_diag_ = cd.value();
  r->ch_timing_ = ct.value();
  // Normal scheduling, a small stack (it serialises into cdr_, not on the stack).
  pthread_attr_t attr;
  pthread_attr_init(&attr);
  pthread_attr_setstacksize(&attr, 256 * 1024);
  const int rc = pthread_create(
      &r->thread_, &attr,
      [](void* self) -> void* {
        static_cast<Recorder*>(self)->run();
        return nullptr;
      },
      r.get());
  pthread_attr_destroy(&attr);
  if (rc != 0) return Error(Errc::kIo, "record: cannot start its thread: %s", std::strerror(rc));
  r->started_ = true;
  pthread_setname_np(r->thread_, "aprt-record");
  return r;
}

Recorder::~Recorder() {
  (void)stop();
}

void Recorder::offer_frame(const FrameBuffer& f, int64_t stamp_ns) noexcept {
  Rings& g = *rings_;
  const uint64_t h = g.frame_head.load(std::memory_order_relaxed);
  if (h - g.frame_tail.load(std::memory_order_acquire) == g.frame_slots ||
      f.info.bytes > o_.max_frame_bytes) {
    g.frames_dropped.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  Rings::Frame& s = g.frames[h % g.frame_slots];
  s.info = f.info;
  s.stamp_ns = stamp_ns;
  std::memcpy(s.data.get(), f.data, f.info.bytes);
  g.frame_head.store(h + 1, std::memory_order_release);
}

void Recorder::offer_pose(const RecordedPose& p) noexcept {
  if (!rings_->poses.push(p)) rings_->poses_dropped.fetch_add(1, std::memory_order_relaxed);
}

void Recorder::offer_status(int64_t stamp_ns, uint8_t level, const char* message,
                            const char* const* keys, const char* const* values,
                            int count) noexcept {
  Rings& g = *rings_;
  Rings::Status& s = g.status_in;
  s.stamp_ns = stamp_ns;
  s.level = level;
  std::snprintf(s.message, sizeof s.message, "%s", message);
  s.count = count < Rings::Status::kMax ? count : Rings::Status::kMax;
  for (int i = 0; i < s.count; ++i) {
    std::snprintf(s.keys[i], sizeof s.keys[i], "%s", keys[i]);
    std::snprintf(s.values[i], sizeof s.values[i], "%s", values[i]);
  }
  if (!g.statuses.push(s)) g.statuses_dropped.fetch_add(1, std::memory_order_relaxed);
}

bool Recorder::drain() noexcept {
  Rings& g = *rings_;
  McapWriter& m = *writer_;
  uint8_t* buf = cdr_.get();
  bool wrote = false;
  const auto put = [&](uint16_t ch, int64_t stamp, size_t n, std::atomic<uint64_t>& count) {
    if (n == 0 || !m.write_message(ch, uint64_t(stamp), uint64_t(stamp), buf, n)) {
      g.write_errors.fetch_add(1, std::memory_order_relaxed);
    } else {
      count.fetch_add(1, std::memory_order_relaxed);
    }
    wrote = true;
  };
  for (uint64_t t = g.frame_tail.load(std::memory_order_relaxed);
       t != g.frame_head.load(std::memory_order_acquire); ++t) {
    const Rings::Frame& f = g.frames[t % g.frame_slots];
    size_t n;
    if (f.info.kind == FrameKind::kScan) {
      n = ros2::pointcloud2_xyzi(buf, cdr_cap_, f.stamp_ns, "lidar",
                                 reinterpret_cast<const float*>(f.data.get()), f.info.scan.points);
    } else {
      n = ros2::image(buf, cdr_cap_, f.stamp_ns, "camera", uint32_t(f.info.width),
                      uint32_t(f.info.height), ros_encoding(f.info.format), uint32_t(f.info.stride),
                      f.data.get(), f.info.bytes);
    }
    put(ch_frame_, f.stamp_ns, n, g.frames_written);
    g.frame_tail.store(t + 1, std::memory_order_release);
  }
  RecordedPose p;
  while (g.poses.pop(&p)) {
    if (p.published) {
      put(ch_pose_, p.stamp_ns,
          ros2::pose_with_covariance(buf, cdr_cap_, p.stamp_ns, o_.frame_id.c_str(), p.position,
                                     p.orientation, p.covariance),
          g.poses_written);
    }
    ros2::PoseTiming t{};
    t.stamp_ns = p.stamp_ns;
    t.index = p.index;
    t.frame_sequence = p.frame_sequence;
    t.flags = p.flags;
    t.state = p.state;
    t.published = p.published;
    std::memcpy(t.position, p.estimate_position, sizeof t.position);
    std::memcpy(t.orientation, p.estimate_orientation, sizeof t.orientation);
    t.capture_ns = p.capture_ns;
    t.inference_start_ns = p.inference_start_ns;
    t.inference_end_ns = p.inference_end_ns;
    t.publish_ns = p.publish_ns;
    put(ch_timing_, p.stamp_ns, ros2::pose_timing(buf, cdr_cap_, o_.frame_id.c_str(), t),
        g.timings_written);
  }
  Rings::Status& s = g.status_out;
  while (g.statuses.pop(&s)) {
    const char* keys[Rings::Status::kMax];
    const char* values[Rings::Status::kMax];
    for (int i = 0; i < s.count; ++i) {
      keys[i] = s.keys[i];
      values[i] = s.values[i];
    }
    put(ch_diag_, s.stamp_ns,
        ros2::diagnostics(buf, cdr_cap_, s.stamp_ns, o_.frame_id.c_str(), s.level, "aprt: pose",
                          s.message, "aprt", keys, values, s.count),
        g.statuses_written);
  }
  g.bytes.store(m.bytes_written(), std::memory_order_relaxed);
  return wrote;
}

void Recorder::run() noexcept {
  for (;;) {
    const bool stopping = stop_.load(std::memory_order_acquire);
    const bool wrote = drain();
    if (stopping) break;  // what was queued before the stop is written
    if (!wrote) {
      const timespec ts{0, 2000000};  // 2 ms: the rings hold far more than that
      nanosleep(&ts, nullptr);
    }
  }
}

Status Recorder::stop() {
  if (stopped_) return close_status_;
  stopped_ = true;
  stop_.store(true, std::memory_order_release);
  if (started_) pthread_join(thread_, nullptr);
  started_ = false;
  close_status_ = writer_ ? writer_->close() : Status(ok());
  if (writer_) rings_->bytes.store(writer_->bytes_written(), std::memory_order_relaxed);
  return close_status_;
}

RecorderStats Recorder::stats() const {
  const Rings& g = *rings_;
  RecorderStats s;
  s.frames = g.frames_written.load(std::memory_order_relaxed);
  s.poses = g.poses_written.load(std::memory_order_relaxed);
  s.statuses = g.statuses_written.load(std::memory_order_relaxed);
  s.frames_dropped = g.frames_dropped.load(std::memory_order_relaxed);
  s.poses_dropped = g.poses_dropped.load(std::memory_order_relaxed);
  s.statuses_dropped = g.statuses_dropped.load(std::memory_order_relaxed);
  s.write_errors = g.write_errors.load(std::memory_order_relaxed);
  s.bytes = g.bytes.load(std::memory_order_relaxed);
  return s;
}

void recorder_summary(const Recorder& r, char* buf, size_t size) {
  const RecorderStats s = r.stats();
  std::snprintf(buf, size,
                "record: %s: %llu frames, %llu poses, %llu diagnostics, %.1f MB; dropped (ring "
                "full) %llu frames, %llu poses, %llu diagnostics; %llu write errors",
                r.path().c_str(), static_cast<unsigned long long>(s.frames),
                static_cast<unsigned long long>(s.poses),
                static_cast<unsigned long long>(s.statuses), double(s.bytes) / 1e6,
                static_cast<unsigned long long>(s.frames_dropped),
                static_cast<unsigned long long>(s.poses_dropped),
                static_cast<unsigned long long>(s.statuses_dropped),
                static_cast<unsigned long long>(s.write_errors));
}

}  // namespace aprt
