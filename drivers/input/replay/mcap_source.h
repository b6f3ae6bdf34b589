// A recorded drive (MCAP, as `aprt run --record` or `ros2 bag record
// --storage mcap` writes it) as a frame source: the messages of one image
// (sensor_msgs/msg/Image) or point-cloud (sensor_msgs/msg/PointCloud2)
// channel, in file order, paced like every replay (fixed rate, the recorded
// log times, or as fast as inference takes them; loop; frame limit). The
// frames keep their recorded header stamps, so the poses of a replayed drive
// carry the drive's own times. Image encodings: rgb8, bgr8, yuv422_yuy2
// (YUYV), yuv422 / uyvy (UYVY), nv12, mono8; anything else is a skipped frame
// with the reason.
#pragma once

#include <memory>
#include <string>

#include "drivers/codec/mcap_reader.h"
#include "drivers/input/frame_source.h"
#include "drivers/input/lidar/point_cloud.h"
#include "drivers/input/replay/replay_pacer.h"

namespace aprt {

class McapSource final : public FrameSource {
 public:
  // `topic` empty: the file's first image or point-cloud channel.
  static Expected<std::unique_ptr<McapSource>> open(const char* path, const std::string& topic,
                                                    const ReplayPacing& pacing,
                                                    const ScanSourceOptions& scans);

  const char* name() const override { return "mcap"; }
  size_t max_frame_bytes() const override { return max_frame_bytes_; }
  Status start() override;
  SourceResult next(FrameBuffer* dst, int64_t timeout_ns) override;
  void stop() override {}
  const Error& error() const override { return error_; }
  void pace_with(const FrameSlot* slot) override { pacer_.pace_with(slot); }
  void note_taken(uint64_t n) override { pacer_.note_taken(n); }

  bool scans() const { return scans_; }
  size_t size() const { return reader_->size(); }
  const McapChannelInfo& channel() const { return reader_->channel(); }
  // The first image's geometry (camera channels).
  int width() const { return width_; }
  int height() const { return height_; }
  PixelFormat format() const { return format_; }
  bool truncated() const { return reader_->truncated(); }

 private:
  McapSource() = default;
  std::unique_ptr<McapReader> reader_;
  std::unique_ptr<PointCloud> cloud_;
  ScanSourceOptions options_;
  ReplayPacer pacer_;
  bool scans_ = false;
  int width_ = 0, height_ = 0;
  PixelFormat format_ = PixelFormat::kRgb24;
  size_t max_frame_bytes_ = 0;
  Error error_;
};

}  // namespace aprt
