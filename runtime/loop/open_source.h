// A configured source created with what the preprocessing needs: a camera
// (replay, V4L2, libcamera) with its frame geometry, or a LiDAR (lidar_replay,
// pointcloud2) delivering gated scans. Start-up only.
#pragma once

#include <memory>

#include "drivers/input/frame_source.h"
#include "runtime/base/image.h"
#include "runtime/config/config.h"

namespace aprt {

struct OpenedSource {
  std::unique_ptr<FrameSource> source;
  int width = 0, height = 0;  // what the source is configured to deliver
  PixelFormat format = PixelFormat::kRgb24;
  size_t frames = 0;   // a replay's length (0 for a device)
  bool scans = false;  // LiDAR scans (an mcap file's channel decides)
};

Expected<OpenedSource> open_source(const Config::Source& src);

}  // namespace aprt
