// Replay of a labelled sequence in the DeepLoc layout: a folder with
// poses.txt ("name x y z qw qx qy qz" per line, '#' comments) and the images
// it names (PNG or JPEG, all of one size), optionally times.txt ("name
// seconds") for the recorded rate, and odometry.txt, the vehicle's speed and
// yaw rate on the recording's clock (drivers/input/odometry.h). The pose list is read at open();
// frames are decoded on demand into caller buffers with the ground truth attached.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "drivers/codec/image_decoder.h"
#include "drivers/input/frame.h"
#include "drivers/input/odometry.h"
#include "drivers/input/replay/pose_list.h"
#include "runtime/base/expected.h"

namespace aprt {

// A sequence without times.txt was recorded at 25 Hz (aprt_synth's drives,
// DeepLoc's): the clock its odometry.txt is on.
inline constexpr double kDefaultFramePeriodS = 0.04;

// The largest replay frame side (a 4096 x 4096 RGB frame: 48 MB).
inline constexpr int kMaxReplaySide = 4096;

class DeeplocReplay {
 public:
  static Expected<std::unique_ptr<DeeplocReplay>> open(const char* folder);

  size_t size() const { return entries_.size(); }
  const ReplayEntry& entry(size_t i) const { return entries_[i]; }
  int width() const { return width_; }
  int height() const { return height_; }
  size_t frame_bytes() const { return size_t(width_) * height_ * 3; }
  bool has_times() const { return has_times_; }
  const char* folder() const { return folder_; }
  // Frame i's time on the recording's clock: times.txt, or i / 25 Hz.
  double recording_time_s(size_t i) const;
  bool has_odometry() const { return !readings_.empty(); }
  // Frame i's odometry reading (odometry.txt integrated from the first
  // frame; a new epoch where it broke off); invalid without odometry.txt or
  // where it does not cover the frame.
  OdometryReading reading(size_t i) const {
    return i < readings_.size() ? readings_[i] : OdometryReading{};
  }
  // The epochs the readings span (a looping replay adds this per loop).
  uint32_t epochs() const { return epochs_; }

  // Decodes frame i into dst (RGB24) and fills its info. A corrupt or
  // missing image is an error naming the file; the caller counts and skips it.
  Status read(size_t i, FrameBuffer* dst, uint64_t sequence, int64_t capture_ns);

 private:
  DeeplocReplay() = default;
  void integrate(const OdometrySeries& od);
  char folder_[512] = {};
  std::vector<ReplayEntry> entries_;
  std::unique_ptr<ImageDecoder> decoder_;
  int width_ = 0, height_ = 0;
  bool has_times_ = false;
  std::vector<OdometryReading> readings_;
  uint32_t epochs_ = 1;
};

}  // namespace aprt
