// The network's raw output turned into a pose, with sanity flags.
//
// Position: de-normalised from the training set's min-max bounds (model
// metadata). Orientation: the quaternion normalised to unit length with w >= 0
// (q and -q are the same rotation). A value that cannot be trusted is never
// silently repaired: it is flagged, and callers must not publish a flagged
// pose as valid.
#pragma once

#include <cstdint>

#include "runtime/engine/model_file.h"

namespace aprt {

inline constexpr uint32_t kPoseNonFinite = 1u << 0;       // NaN/Inf in the raw output
inline constexpr uint32_t kPoseQuatDegenerate = 1u << 1;  // |q| too small to normalise
inline constexpr uint32_t kPoseQuatNorm = 1u << 2;        // raw |q| far from 1 (not in [0.5, 2])
inline constexpr uint32_t kPoseOutOfBounds = 1u << 3;     // outside the map bounds plus margin

struct PoseEstimate {
  double position[3] = {};               // metres, map frame of the training data
  double orientation[4] = {1, 0, 0, 0};  // w, x, y, z; unit length, w >= 0
  float raw_quat_norm = 0.0f;
  uint32_t flags = 0;

  bool valid() const { return flags == 0; }
};

// `bounds_margin` widens the bounds by that fraction of their extent on each side.
// @rt: constant time, no allocation.
PoseEstimate decode_pose(const float raw[7], const ModelMeta& meta,
                         float bounds_margin = 0.1f) noexcept;

// Short text for the flags ("ok", "non-finite,out-of-bounds", ...) into `buf`.
const char* pose_flags_text(uint32_t flags, char* buf, int size) noexcept;

}  // namespace aprt
