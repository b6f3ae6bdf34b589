// A camera frame in preallocated storage, with where and when it came from.
#pragma once

#include <cstddef>
#include <cstdint>

#include "kernels/common/image_types.h"

namespace aprt {

struct FrameInfo {
  uint64_t sequence = 0;   // per source, from 0; gaps are frames the source lost
  int64_t capture_ns = 0;  // CLOCK_MONOTONIC time of capture (driver timestamp)
  int width = 0, height = 0;
  kernels::PixelFormat format = kernels::PixelFormat::kRgb24;
  size_t stride = 0;    // bytes per row
  size_t bytes = 0;     // valid bytes in the buffer
  uint32_t source = 0;  // camera index
  // Ground truth, when the source has it (replay of a labelled sequence).
  bool has_truth = false;
  double truth_position[3] = {};
  double truth_orientation[4] = {1, 0, 0, 0};  // w x y z
  char name[128] = {};                         // e.g. the image file of a replayed frame
};

struct FrameBuffer {
  FrameInfo info;
  uint8_t* data = nullptr;
  size_t capacity = 0;

  kernels::ImageView view() const {
    return {data, info.format, info.width, info.height, info.stride};
  }
};

}  // namespace aprt
