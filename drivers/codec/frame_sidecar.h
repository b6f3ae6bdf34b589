// The text beside a frame saved by `aprt run --save-frame N:FRAME.raw`
// (FRAME.raw.txt): the frame's geometry, where it came from and the pose the
// run computed. `aprt infer` reads it back to recompute the pose elsewhere
// (the HIL rig), so it is outside input: parsed strictly (fuzzed:
// tests/fuzz/frame_sidecar_fuzz.cc) and checked against the bytes it claims
// before one pixel is read.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "runtime/base/expected.h"
#include "runtime/base/image.h"

namespace aprt {

struct FrameSidecar {
  PixelFormat format = PixelFormat::kRgb24;
  int width = 0, height = 0;
  size_t stride = 0;  // bytes per row
  size_t bytes = 0;   // of FRAME.raw
  bool have_pose = false;
  double pose[7] = {};  // x y z qw qx qy qz
};

// Largest frame side and file a sidecar may describe.
inline constexpr int kMaxSidecarSide = 16384;
inline constexpr size_t kMaxSidecarFrameBytes = size_t(1) << 30;

// Keys: format, width, height, stride, bytes (required); pose (7 finite
// numbers, optional); name, model, isa, flags (informative). Refused, with
// the line: an unknown pixel format, a size outside [1, kMaxSidecarSide], a
// stride below the format's row or above 16 x its row, `bytes` smaller than
// the rows span (image_span) or above kMaxSidecarFrameBytes, a key given
// twice, a malformed number.
Expected<FrameSidecar> parse_frame_sidecar(std::string_view text, const char* path);

// The sidecar text for a frame (what parse_frame_sidecar reads back).
std::string format_frame_sidecar(const FrameSidecar& s, const char* name, const char* model,
                                 const char* isa, uint32_t flags);

}  // namespace aprt
