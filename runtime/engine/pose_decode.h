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
inline constexpr uint32_t kPoseNoConfidence = 1u << 4;    // the confidence outputs are not finite

struct PoseEstimate {
  double position[3] = {};               // metres, map frame of the training data
  double orientation[4] = {1, 0, 0, 0};  // w, x, y, z; unit length, w >= 0
  float raw_quat_norm = 0.0f;
  uint32_t flags = 0;
  // The model's own confidence for this frame (files with 'uncertainty',
  // FORMAT.md 1.3; an ensemble's members' spread included, 1.5): one
  // standard deviation of the position error per map axis (m) and of the
  // rotation error about the camera's x, y, z axes (rad; z is yaw). Without
  // it, false and zeros (the outputs use the validation error instead).
  bool has_sigma = false;
  double sigma_position_m[3] = {};
  double sigma_rotation_rad[3] = {};

  bool valid() const { return flags == 0; }
};

// raw: the engine's output, 7 values, or 13 when meta.has_uncertainty, or
// 13 per member of an ensemble when meta.member_outputs (the loader
// guarantees it): the members are merged first (ensemble_merge.h), and their
// spread joins the confidence -- a frame whose members disagree, most often
// one of them on another street, says so itself. `bounds_margin` widens the
// bounds by that fraction of their extent on each side.
// @rt: constant time, no allocation.
PoseEstimate decode_pose(const float* raw, const ModelMeta& meta,
                         float bounds_margin = 0.1f) noexcept;

}  // namespace aprt
