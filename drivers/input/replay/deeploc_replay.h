// Replay of a labelled sequence in the DeepLoc layout: a folder with
// poses.txt ("name x y z qw qx qy qz" per line, '#' comments) and the images
// it names (PNG or JPEG, all of one size), optionally times.txt ("name
// seconds") for the recorded rate. The pose list is read at open(); frames
// are decoded on demand into caller buffers with the ground truth attached.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "drivers/codec/image_decoder.h"
#include "drivers/input/frame.h"
#include "drivers/input/replay/pose_list.h"
#include "runtime/base/expected.h"

namespace aprt {

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

  // Decodes frame i into dst (RGB24) and fills its info. A corrupt or
  // missing image is an error naming the file; the caller counts and skips it.
  Status read(size_t i, FrameBuffer* dst, uint64_t sequence, int64_t capture_ns);

 private:
  DeeplocReplay() = default;
  char folder_[512] = {};
  std::vector<ReplayEntry> entries_;
  std::unique_ptr<ImageDecoder> decoder_;
  int width_ = 0, height_ = 0;
  bool has_times_ = false;
};

}  // namespace aprt
