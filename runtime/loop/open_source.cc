#include "runtime/loop/open_source.h"

#include "drivers/input/camera/libcamera_source.h"
#include "drivers/input/camera/v4l2_source.h"
#include "drivers/input/lidar/lidar_replay_source.h"
#include "drivers/input/pointcloud2/pointcloud2_source.h"
#include "drivers/input/replay/mcap_source.h"
#include "drivers/input/replay/replay_source.h"

namespace aprt {
namespace {

// The point gate of a LiDAR source (drivers/input/lidar/point_cloud.h) from the configuration.
ScanSourceOptions scan_options(const Config::Source& src) {
  ScanSourceOptions o;
  o.max_points = size_t(src.lidar.max_points);
  const double* r = src.lidar.region;
  o.region = {float(r[0]), float(r[1]), float(r[2]), float(r[3]), float(r[4]), float(r[5])};
  return o;
}

ReplayPacing pacing_of(const Config::Source& src) {
  return {src.replay.rate_hz, src.replay.recorded, src.replay.loop, uint64_t(src.replay.frames)};
}

}  // namespace

Expected<OpenedSource> open_source(const Config::Source& src) {
  OpenedSource o;
  switch (src.type) {
    case SourceType::kReplay: {
      auto replay = ReplaySource::open(src.replay.path.c_str(), pacing_of(src));
      if (!replay) return replay.error();
      o.width = replay.value()->replay().width();
      o.height = replay.value()->replay().height();
      o.frames = replay.value()->replay().size();
      o.source = std::move(replay.value());
      return o;
    }
    case SourceType::kV4l2: {
      V4l2Options vo;
      vo.device = src.v4l2.device;
      vo.width = src.v4l2.width;
      vo.height = src.v4l2.height;
      vo.format = src.v4l2.format;
      vo.fps = src.v4l2.fps;
      vo.buffers = src.v4l2.buffers;
      auto dev = V4l2Source::create(vo);
      if (!dev) return dev.error();
      o.width = vo.width;
      o.height = vo.height;
      o.format = dev.value()->format();
      o.source = std::move(dev.value());
      return o;
    }
    case SourceType::kLibcamera: {
      LibcameraOptions lo;
      lo.camera = src.libcamera.camera;
      lo.width = src.libcamera.width;
      lo.height = src.libcamera.height;
      lo.format = src.libcamera.format;
      lo.role = src.libcamera.role;
      lo.buffers = src.libcamera.buffers;
      lo.fps = src.libcamera.fps;
      auto dev = LibcameraSource::create(lo);
      if (!dev) return dev.error();
      o.width = lo.width;
      o.height = lo.height;
      o.format = dev.value()->format();
      o.source = std::move(dev.value());
      return o;
    }
    case SourceType::kMcap: {
      auto m = McapSource::open(src.replay.path.c_str(), src.mcap.topic, pacing_of(src),
                                scan_options(src));
      if (!m) return m.error();
      o.scans = m.value()->scans();
      o.width = m.value()->width();
      o.height = m.value()->height();
      o.format = m.value()->format();
      o.frames = m.value()->size();
      o.source = std::move(m.value());
      return o;
    }
    case SourceType::kLidarReplay: {
      auto replay =
          LidarReplaySource::open(src.replay.path.c_str(), pacing_of(src), scan_options(src));
      if (!replay) return replay.error();
      o.frames = replay.value()->size();
      o.scans = true;
      o.source = std::move(replay.value());
      return o;
    }
    case SourceType::kPointCloud2: {
      PointCloud2Options po;
      po.domain = uint32_t(src.pointcloud2.domain);
      po.topic = src.pointcloud2.topic;
      po.depth = src.pointcloud2.depth;
      po.reliable = src.pointcloud2.reliable;
      po.loopback_only = src.pointcloud2.loopback_only;
      auto dev = PointCloud2Source::create(po, scan_options(src));
      if (!dev) return dev.error();
      o.scans = true;
      o.source = std::move(dev.value());
      return o;
    }
  }
  return Error(Errc::kUnsupported, "run: source type '%s' is not available in this build",
               source_type_name(src.type));
}

}  // namespace aprt
