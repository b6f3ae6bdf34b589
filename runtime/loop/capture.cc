#include "runtime/loop/capture.h"

#include <time.h>

#include <algorithm>
#include <cstdio>
#include <new>

#include "runtime/loop/model_loader.h"
#include "runtime/loop/open_source.h"
#include "runtime/loop/recorder.h"
#include "runtime/pose/pose_geometry.h"

namespace aprt {

Expected<std::unique_ptr<CaptureChannel>> open_channel(const Config::Camera& cam, size_t index,
                                                       size_t count, const Engine& engine,
                                                       const std::string& model, size_t* frames) {
  auto ch = std::unique_ptr<CaptureChannel>(new (std::nothrow) CaptureChannel());
  if (!ch) return Error(Errc::kOutOfMemory, "run: out of memory");
  ch->index = index;
  ch->name = cam.name;
  ch->thread_name = count == 1 ? "aprt-capture" : "aprt-cap" + std::to_string(index);
  ch->source_type = cam.source.type;
  ch->base_from_sensor =
      RigidTransform::from_xyz_rpy(cam.sensor_xyz, cam.sensor_rpy_deg).isometry();
  const Config::Source& src = cam.source;
  // Before any device is opened: a camera model needs a camera, a LiDAR model a LiDAR.
  if (Status fit = model_fits_source(engine.meta(), src, model); !fit) return fit.error();
  auto opened = open_source(src);
  if (!opened) {
    if (count == 1) return opened.error();
    return Error(opened.error().code(), "run: camera %s: %s", cam.name.c_str(),
                 opened.error().message());
  }
  if (Status fit = model_fits_source(engine.meta(), src, model, opened->scans ? 1 : 0); !fit) {
    return fit.error();
  }
  *frames = opened->frames;
  ch->frame_limit = src.type == SourceType::kV4l2          ? uint64_t(src.v4l2.frames)
                    : src.type == SourceType::kLibcamera   ? uint64_t(src.libcamera.frames)
                    : src.type == SourceType::kPointCloud2 ? uint64_t(src.pointcloud2.frames)
                                                           : 0;
  ch->source = std::move(opened->source);
  // A camera is started here, once: a configuration it can never deliver
  // (a size or format it does not offer) is refused at start-up, naming what
  // it offers. One that is absent or fails otherwise is retried with back-off
  // by its capture thread.
  if (src.type == SourceType::kV4l2 || src.type == SourceType::kLibcamera) {
    Status s = ch->source->start();
    if (!s && s.error().code() == Errc::kUnsupported) {
      if (count == 1) return s.error();
      return Error(s.error().code(), "run: camera %s: %s", cam.name.c_str(), s.error().message());
    }
    ch->source_started = bool(s);
    if (!s) {
      std::fprintf(stderr, "aprt run: %s (retrying with back-off)\n", s.error().message());
      ch->failed.store(true);
    }
  }
  auto slot = FrameSlot::create(ch->source->max_frame_bytes());
  if (!slot) return slot.error();
  ch->slot = std::move(slot.value());
  if (ch->replay() && src.replay.rate_hz == 0 && !src.replay.recorded) {
    ch->source->pace_with(ch->slot.get());
  }
  auto input = opened->scans
                   ? EngineInput::for_scans(engine, size_t(src.lidar.max_points))
                   : EngineInput::for_images(engine, opened->format, opened->width, opened->height);
  if (!input) {
    return Error(input.error().code(), "run: camera %s: %s", cam.name.c_str(),
                 input.error().message());
  }
  ch->input = std::move(input.value());
  return ch;
}

void* capture_thread(void* channel) {
  CaptureChannel& c = *static_cast<CaptureChannel*>(channel);
  LoopShared& shared = *c.shared;
  const FaultInjector& faults = *c.faults;
  const size_t channels = c.run_channels;
  const bool device = !c.replay();
  const bool primary = c.index == 0;  // deliberate camera stalls hit the trigger camera
  const char* prefix = channels > 1 ? c.name.c_str() : "";
  const char* sep = channels > 1 ? ": " : "";
  if (c.source_started || c.failed.load()) {
    // Started (or reported failing) at open_channel(): next() reopens with back-off.
  } else if (Status s = c.source->start(); !s) {
    std::fprintf(stderr, "aprt run: %s%s%s%s\n", prefix, sep, s.error().message(),
                 device ? " (retrying with back-off)" : "");
    c.failed.store(true);
    if (!device) {  // a replay that cannot start will not start later
      c.done.store(true);
      return nullptr;
    }
  }
  while (!shared.stop.load(std::memory_order_acquire)) {
    c.beat.store(monotonic_ns(), std::memory_order_release);
    // The back buffer is reused: a stamp left from the frame it held before
    // must not pass for this frame's (only sources with their own clock set one).
    c.slot->back().info.source_stamp_ns = 0;
    switch (c.source->next(&c.slot->back(), kLoopWaitNs)) {
      case SourceResult::kFrame: {
        if (!c.source->driver_timestamps()) {
          c.slot->back().info.capture_ns = monotonic_ns();  // arrival, for frame age
        }
        c.slot->back().info.source = uint32_t(c.index);
        if (c.recorder) {  // a copy into the recorder's ring, never a wait
          // The frame's wall-clock stamp, fixed now: the recorded frame and
          // the pose published for it carry the same stamp.
          FrameInfo& fi = c.slot->back().info;
          if (!fi.source_stamp_ns)
            fi.source_stamp_ns = fi.capture_ns + realtime_ns() - monotonic_ns();
          c.recorder->offer_frame(c.slot->back(), fi.source_stamp_ns);
        }
        c.slot->publish();
        const uint64_t n = c.captured.fetch_add(1);
        if (const int64_t stall = primary ? faults.stall_ns(n) : 0) {
          // The camera delivers nothing; the thread stays alive and keeps beating.
          const int64_t until = monotonic_ns() + stall;
          while (!shared.stop.load(std::memory_order_acquire) && monotonic_ns() < until) {
            const timespec ts{0, 5000000};
            nanosleep(&ts, nullptr);
            c.beat.store(monotonic_ns(), std::memory_order_release);
          }
        }
        if (c.failed.exchange(false, std::memory_order_acq_rel)) {
          std::fprintf(stderr, "aprt run: %s delivers frames again\n", c.source->name());
        }
        if (c.frame_limit != 0 && n + 1 >= c.frame_limit) {  // a bounded device run: done
          c.done.store(true, std::memory_order_release);
          return nullptr;
        }
        break;
      }
      case SourceResult::kTimeout: break;
      case SourceResult::kSkipped:
        shared.frames_skipped.fetch_add(1, std::memory_order_relaxed);
        std::fprintf(stderr, "aprt run: frame skipped: %s\n", c.source->error().message());
        break;
      case SourceResult::kEndOfStream:
        c.done.store(true, std::memory_order_release);
        return nullptr;
      case SourceResult::kFailed:
        if (!c.failed.exchange(true, std::memory_order_acq_rel)) {
          std::fprintf(stderr, "aprt run: %s\n", c.source->error().message());
        }
        break;
    }
  }
  c.done.store(true, std::memory_order_release);
  return nullptr;
}

const FrameBuffer* take_frame(CaptureChannel& c, int64_t deadline_ns) noexcept {
  const FrameBuffer* f = nullptr;
  for (;;) {
    const uint32_t seen = c.slot->published();
    if (c.slot->take(&f)) break;
    const int64_t left = deadline_ns - monotonic_ns();
    if (left <= 0 || c.done.load(std::memory_order_acquire)) return nullptr;
    c.slot->wait(seen, std::min(left, kLoopWaitNs));
  }
  if (c.replay()) c.source->note_taken(f->info.sequence + 1);
  return f;
}

}  // namespace aprt
