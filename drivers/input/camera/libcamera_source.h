// A libcamera camera as a frame source (libcamera 0.0.3, Debian 12's; the
// calls used are the ones that have stayed put since: CameraManager, Camera,
// CameraConfiguration, FrameBufferAllocator, Request with reuse()).
//
// Camera by id (as libcamera names it, e.g. "\_SB_.PCI0-2:1.0-046d:0825") or
// by index; stream role, size and pixel format from the configuration,
// validated (an adjusted format is refused with what the camera offers). A
// fixed set of requests is created at start and reused: libcamera completes a
// request on its own thread, the handler only pushes it into a fixed-capacity
// ring and wakes the capture thread through an eventfd; next() waits on that
// with its timeout, copies (or, for MJPEG, decodes) the frame into aprt's
// preallocated slot buffer with the sensor timestamp, and queues the request
// again. A camera that disconnects is closed, reported, and reopened with
// back-off from next(), as the V4L2 source does.
//
// Builds without libcamera (the aarch64 sysroot, a minimal host) get a
// create() that says so.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "drivers/input/frame_source.h"

namespace aprt {

struct LibcameraOptions {
  std::string camera;  // id, or a decimal index into libcamera's list; empty: the first camera
  int width = 640, height = 480;
  std::string format = "YUYV";      // YUYV UYVY NV12 RGB24 BGR24 MJPEG (decoded to RGB24)
  std::string role = "viewfinder";  // viewfinder | video | still
  int buffers = 4;
  int fps = 30;  // FrameDurationLimits at start; a camera without the control keeps its own rate
  int64_t retry_ns = 1000000000;  // first reopen delay; doubles up to 8x
};

class LibcameraSource final : public FrameSource {
 public:
  static Expected<std::unique_ptr<LibcameraSource>> create(const LibcameraOptions& o);
  ~LibcameraSource() override;

  const char* name() const override { return "libcamera"; }
  size_t max_frame_bytes() const override;
  bool driver_timestamps() const override { return true; }
  Status start() override;
  SourceResult next(FrameBuffer* dst, int64_t timeout_ns) override;
  void stop() override;
  const Error& error() const override;

  PixelFormat format() const;
  uint64_t reopens() const;
  // The cameras libcamera sees on this machine, one "index: id (model)" per line.
  static std::string list_cameras();

  struct Impl;

 private:
  LibcameraSource() = default;
  std::unique_ptr<Impl> impl_;
};

}  // namespace aprt
