// A V4L2 capture device as a frame source: format negotiation, mmap
// streaming with a fixed buffer count, poll with a timeout before every
// dequeue, the driver's monotonic timestamps carried with each frame, and a
// device that vanishes (ENODEV/EIO) closed cleanly, reported, and reopened
// with back-off from next() itself -- the capture thread never blocks longer
// than its timeout. Frames are copied into the caller's (FrameSlot's) buffer
// and the V4L2 buffer is queued back at once: the driver never waits on aprt.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "drivers/codec/image_decoder.h"
#include "drivers/input/frame_source.h"

struct v4l2_buffer;

namespace aprt {

struct V4l2Options {
  // A path, or a card name / bus_info (drivers/input/camera/v4l2_devices.h).
  std::string device = "/dev/video0";
  int width = 640, height = 480;
  std::string format = "YUYV";  // YUYV UYVY NV12 RGB24 BGR24 MJPEG (decoded to RGB24)
  int fps = 30;
  int buffers = 4;
  int64_t retry_ns = 1000000000;  // first reopen delay; doubles up to 8x
};

class V4l2Source final : public FrameSource {
 public:
  // Checks the options; the device is opened by start().
  static Expected<std::unique_ptr<V4l2Source>> create(const V4l2Options& o);
  ~V4l2Source() override;

  const char* name() const override { return "v4l2"; }
  size_t max_frame_bytes() const override { return max_bytes_; }
  bool driver_timestamps() const override { return true; }
  // Opens, negotiates, maps and starts streaming. Errors name the device and
  // what it offers (e.g. the formats it lists when ours is not among them).
  Status start() override;
  SourceResult next(FrameBuffer* dst, int64_t timeout_ns) override;
  void stop() override;
  const Error& error() const override { return error_; }

  // What was negotiated (valid after start()).
  int width() const { return width_; }
  int height() const { return height_; }
  PixelFormat format() const { return format_; }
  uint64_t reopens() const { return reopens_; }

 private:
  V4l2Source() = default;
  Status open_device();
  void close_device();
  void fill_info(FrameBuffer* dst, const v4l2_buffer& b, size_t bytes);
  std::unique_ptr<ImageDecoder> decoder_;  // MJPEG only
  V4l2Options o_;
  uint32_t fourcc_ = 0;
  PixelFormat format_ = PixelFormat::kYuyv;
  size_t max_bytes_ = 0;
  int fd_ = -1;
  int width_ = 0, height_ = 0;
  size_t stride_ = 0;
  static constexpr int kMaxBuffers = 32;
  void* maps_[kMaxBuffers] = {};
  size_t lengths_[kMaxBuffers] = {};
  int mapped_ = 0;
  bool streaming_ = false;
  int64_t retry_at_ns_ = 0, retry_delay_ns_ = 0;
  uint64_t reopens_ = 0, sequence_ = 0;
  Error error_;
};

}  // namespace aprt
