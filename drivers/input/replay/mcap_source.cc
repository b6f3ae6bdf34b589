#include "drivers/input/replay/mcap_source.h"

#include <cstdio>
#include <cstring>
#include <new>

#include "drivers/codec/ros2_cdr.h"
#include "drivers/input/pointcloud2/pointcloud2_decode.h"

namespace aprt {
namespace {

constexpr const char* kImage = "sensor_msgs/msg/Image";
constexpr const char* kCloud = "sensor_msgs/msg/PointCloud2";

bool format_of(const char* encoding, PixelFormat* f) {
  static const struct {
    const char* name;
    PixelFormat format;
  } kMap[] = {{"rgb8", PixelFormat::kRgb24},       {"bgr8", PixelFormat::kBgr24},
              {"yuv422_yuy2", PixelFormat::kYuyv}, {"yuyv", PixelFormat::kYuyv},
              {"yuv422", PixelFormat::kUyvy},      {"uyvy", PixelFormat::kUyvy},
              {"nv12", PixelFormat::kNv12},        {"mono8", PixelFormat::kGray8}};
  for (const auto& m : kMap) {
    if (std::strcmp(encoding, m.name) == 0) {
      *f = m.format;
      return true;
    }
  }
  return false;
}

}  // namespace

Expected<std::unique_ptr<McapSource>> McapSource::open(const char* path, const std::string& topic,
                                                       const ReplayPacing& pacing,
                                                       const ScanSourceOptions& scans) {
  std::unique_ptr<McapSource> s(new (std::nothrow) McapSource());
  if (!s) return Error(Errc::kOutOfMemory, "mcap: out of memory");
  auto r = McapReader::open(path, topic, {kImage, kCloud});
  if (!r) return r.error();
  s->reader_ = std::move(r.value());
  const McapChannelInfo& ch = s->reader_->channel();
  if (ch.schema_name == kCloud) {
    s->scans_ = true;
    auto cloud = PointCloud::create(scans.max_points);
    if (!cloud) return cloud.error();
    s->cloud_ = std::move(cloud.value());
    s->max_frame_bytes_ = scans.max_points * sizeof(LidarPoint);
  } else if (ch.schema_name == kImage) {
    // The first frame sets the geometry the engine's input is prepared for.
    size_t n = 0;
    auto bytes = s->reader_->read(0, &n);
    if (!bytes) return bytes.error();
    ros2::ImageMsg m;
    if (!ros2::read_image(bytes.value(), n, &m)) {
      return Error(Errc::kInvalidArgument, "mcap: %s: the first message of %s is not a CDR image",
                   path, ch.topic.c_str());
    }
    if (!format_of(m.encoding, &s->format_)) {
      return Error(Errc::kUnsupported,
                   "mcap: %s: %s is %s-encoded; aprt replays rgb8, bgr8, yuv422_yuy2, yuv422, "
                   "nv12 and mono8",
                   path, ch.topic.c_str(), m.encoding);
    }
    s->width_ = int(m.width);
    s->height_ = int(m.height);
    s->max_frame_bytes_ = s->reader_->max_message_bytes();
  } else {
    return Error(Errc::kUnsupported, "mcap: %s: channel %s carries %s, not images or point clouds",
                 path, ch.topic.c_str(), ch.schema_name.c_str());
  }
  if (s->reader_->truncated()) {
    std::fprintf(stderr,
                 "mcap: %s ends inside a record (a recording cut short?): replaying its %zu "
                 "whole messages on %s\n",
                 path, s->reader_->size(), ch.topic.c_str());
  }
  s->options_ = scans;
  s->pacer_.configure(pacing);
  return s;
}

Status McapSource::start() {
  pacer_.start(double(reader_->log_time_ns(0)) * 1e-9);
  return ok();
}

SourceResult McapSource::next(FrameBuffer* dst, int64_t timeout_ns) {
  size_t i = 0;
  const SourceResult r = pacer_.next(
      reader_->size(), [this](size_t k) { return double(reader_->log_time_ns(k)) * 1e-9; },
      timeout_ns, &i);
  if (r != SourceResult::kFrame) return r;
  size_t n = 0;
  auto bytes = reader_->read(i, &n);
  if (!bytes) {
    error_ = bytes.error();
    return SourceResult::kSkipped;
  }
  FrameInfo& f = dst->info;
  if (scans_) {
    ros2::PointCloud2Msg m;
    if (!ros2::read_pointcloud2(bytes.value(), n, &m)) {
      error_ = Error(Errc::kInvalidArgument, "mcap: message %zu is not a CDR PointCloud2", i);
      return SourceResult::kSkipped;
    }
    PointFieldView fields[ros2::PointCloud2Msg::kMaxFields];
    for (int k = 0; k < m.n_fields; ++k) {
      fields[k] = {m.fields[k].name, m.fields[k].offset, m.fields[k].datatype, m.fields[k].count};
    }
    const PointCloud2View v{m.height,           m.width,        fields,
                            size_t(m.n_fields), m.is_bigendian, m.point_step,
                            m.row_step,         m.data,         m.size};
    CloudRefusal why = CloudRefusal::kNone;
    if (Status s = decode_pointcloud2(v, options_.region, cloud_.get(), &why); !s) {
      error_ = Error(s.error().code(), "mcap: message %zu: %s", i, s.error().message());
      return SourceResult::kSkipped;
    }
    copy_scan(*cloud_, dst);
    f.source_stamp_ns = m.stamp_ns;
  } else {
    ros2::ImageMsg m;
    if (!ros2::read_image(bytes.value(), n, &m)) {
      error_ = Error(Errc::kInvalidArgument, "mcap: message %zu is not a CDR image", i);
      return SourceResult::kSkipped;
    }
    PixelFormat fmt;
    if (!format_of(m.encoding, &fmt) || fmt != format_ || int(m.width) != width_ ||
        int(m.height) != height_ || m.step < min_stride(fmt, width_) ||
        m.size < image_span(fmt, width_, height_, m.step) || m.size > dst->capacity) {
      error_ = Error(Errc::kInvalidArgument,
                     "mcap: message %zu: a %ux%u %s image of %zu bytes (step %u) where the drive "
                     "began with %dx%d %s",
                     i, m.width, m.height, m.encoding, m.size, m.step, width_, height_,
                     pixel_format_name(format_));
      return SourceResult::kSkipped;
    }
    std::memcpy(dst->data, m.data, m.size);
    f.kind = FrameKind::kImage;
    f.width = width_;
    f.height = height_;
    f.format = format_;
    f.stride = m.step;
    f.bytes = m.size;
    f.source_stamp_ns = m.stamp_ns;
  }
  f.sequence = pacer_.delivered();
  f.capture_ns = monotonic_ns();
  f.has_truth = false;
  std::snprintf(f.name, sizeof f.name, "message %zu", i);
  return SourceResult::kFrame;
}

}  // namespace aprt
