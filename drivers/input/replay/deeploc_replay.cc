#include "drivers/input/replay/deeploc_replay.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <new>

#include "runtime/base/check.h"
#include "runtime/base/file_io.h"

namespace aprt {

namespace {
constexpr size_t kMaxReplayFileBytes = size_t(64) << 20;  // the largest frame file probed
}  // namespace

double DeeplocReplay::recording_time_s(size_t i) const {
  return has_times_ ? entries_[i].time_s : double(i) * kDefaultFramePeriodS;
}

// Each frame's reading: the motion from the frame before composed onto its
// reading; where the odometry does not cover a step, a new epoch from zero.
void DeeplocReplay::integrate(const OdometrySeries& od) {
  readings_.assign(entries_.size(), OdometryReading{});
  uint32_t epoch = 0;
  for (size_t i = 0; i < entries_.size(); ++i) {
    OdometryReading& r = readings_[i];
    const double t = recording_time_s(i);
    PlanarMotion m;
    if (i > 0 && readings_[i - 1].valid && od.motion(recording_time_s(i - 1), t, &m)) {
      const OdometryReading& p = readings_[i - 1];
      r = p;
      r.x += std::cos(p.yaw) * m.dx - std::sin(p.yaw) * m.dy;
      r.y += std::sin(p.yaw) * m.dx + std::cos(p.yaw) * m.dy;
      r.yaw += m.dyaw;
      r.distance_m += m.distance_m;
    } else if (od.motion(t, t, &m)) {
      if (i > 0) ++epoch;
      r = OdometryReading{};
      r.valid = true;
      r.epoch = epoch;
    } else {
      r = OdometryReading{};  // not covered
    }
    r.t_s = t;
  }
  epochs_ = epoch + 1;
}

Expected<std::unique_ptr<DeeplocReplay>> DeeplocReplay::open(const char* folder) {
  std::unique_ptr<DeeplocReplay> r(new (std::nothrow) DeeplocReplay());
  APRT_ENSURE(r != nullptr, Errc::kOutOfMemory, "replay: out of memory");
  APRT_ENSURE(std::strlen(folder) < sizeof r->folder_ - 1, Errc::kInvalidArgument,
              "replay: folder path too long");
  std::snprintf(r->folder_, sizeof r->folder_, "%s", folder);
  char path[768];
  std::snprintf(path, sizeof path, "%s/poses.txt", folder);
  if (Status st = read_pose_list(path, &r->entries_); !st) return st.error();
  // Optional recorded times: absent is fine, present must be right.
  std::snprintf(path, sizeof path, "%s/times.txt", folder);
  if (access(path, F_OK) == 0) {
    std::string text;
    if (Status st = read_input_file(path, kMaxPoseListBytes, "replay: times", &text); !st) {
      return st.error();
    }
    if (Status st = parse_times(text, path, &r->entries_); !st) return st.error();
    r->has_times_ = true;
  }
  // Optional odometry: absent is fine, present must be right.
  std::snprintf(path, sizeof path, "%s/odometry.txt", folder);
  if (access(path, F_OK) == 0) {
    auto od = OdometrySeries::load(path);
    if (!od) return od.error();
    r->integrate(od.value());
  }
  auto dec = ImageDecoder::create(kMaxReplayFileBytes);
  if (!dec) return dec.error();
  r->decoder_ = std::move(dec.value());
  std::snprintf(path, sizeof path, "%s/%s", folder, r->entries_[0].name);
  auto first = r->decoder_->probe(path);
  if (!first) return first.error();
  // The first frame sizes the frame slot: a header may not claim more than a
  // frame can be (every later frame must then match it).
  APRT_ENSURE(first->width <= kMaxReplaySide && first->height <= kMaxReplaySide, Errc::kTooLarge,
              "replay: %s claims %dx%d pixels, more than the %dx%d a replay frame may have", path,
              first->width, first->height, kMaxReplaySide, kMaxReplaySide);
  r->width_ = first->width;
  r->height_ = first->height;
  // Probed with the largest buffer; kept with one for files of this size:
  // twice the raw RGB plus 1 MiB holds any PNG (stored blocks) or JPEG
  // (quality 100, 4:4:4) of these dimensions. Under mlockall the 64 MiB
  // would all be locked and resident.
  const size_t fit = std::min(kMaxReplayFileBytes,
                              size_t(first->width) * size_t(first->height) * 6 + (size_t(1) << 20));
  auto sized = ImageDecoder::create(fit);
  if (!sized) return sized.error();
  r->decoder_ = std::move(sized.value());
  return r;
}

Status DeeplocReplay::read(size_t i, FrameBuffer* dst, uint64_t sequence, int64_t capture_ns) {
  const ReplayEntry& e = entries_[i];
  char path[768];
  std::snprintf(path, sizeof path, "%s/%s", folder_, e.name);
  auto img = decoder_->decode(path, dst->data, dst->capacity);
  if (!img) return img.error();
  APRT_ENSURE(img->width == width_ && img->height == height_, Errc::kShapeMismatch,
              "replay: %s is %dx%d, the sequence is %dx%d", path, img->width, img->height, width_,
              height_);
  FrameInfo& f = dst->info;
  f.sequence = sequence;
  f.capture_ns = capture_ns;
  f.width = img->width;
  f.height = img->height;
  f.format = PixelFormat::kRgb24;
  f.stride = size_t(img->width) * 3;
  f.bytes = img->bytes;
  f.has_truth = true;
  for (int k = 0; k < 3; ++k) f.truth_position[k] = e.position[k];
  for (int k = 0; k < 4; ++k) f.truth_orientation[k] = e.orientation[k];
  std::snprintf(f.name, sizeof f.name, "%s", e.name);
  f.odometry = reading(i);
  return ok();
}

}  // namespace aprt
