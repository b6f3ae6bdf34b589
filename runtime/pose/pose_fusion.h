// Several cameras' estimates of one vehicle pose fused into one, with outlier
// rejection (issue #8's multi-camera mode).
//
// Each camera's network estimate is its own pose in the training map frame;
// brought to base_link with that camera's extrinsic (T_map_base_i =
// T_map_sensor_i * T_base_sensor_i^-1) every camera estimates the same thing.
// The fusion then:
//   1. keeps the usable estimates (a frame arrived and its pose has no flag);
//   2. picks the medoid: the estimate with the smallest summed distance to the
//      others, position and angle each measured in units of its threshold
//      (robust to a minority of wild estimates, unlike a mean);
//   3. counts as inliers the estimates within max_position_spread_m and
//      max_orientation_spread of the medoid;
//   4. is valid only with a quorum: at least min_agreeing inliers and a strict
//      majority of the usable estimates (two cameras that disagree give no
//      pose rather than a coin toss);
//   5. averages the inliers: mean position, and the quaternion that maximises
//      sum (q_i . q)^2 (the principal eigenvector of sum q_i q_i^T -- Markley
//      et al., "Averaging Quaternions", JGCD 2007), sign-free.
// Fixed-size Eigen types only: no allocation, constant time for the fixed
// maximum camera count.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>

#include "runtime/engine/pose_decode.h"
#include "runtime/pose/pose_geometry.h"

namespace aprt {

inline constexpr int kMaxFusedCameras = 8;

struct FusionParams {
  double max_position_spread_m = 5.0;
  double max_orientation_spread_rad = 10.0 * M_PI / 180.0;
  int min_agreeing = 1;
};

// One camera's estimate, already in base_link (training map frame).
struct CameraEstimate {
  bool present = false;  // a frame arrived for this cycle
  uint32_t flags = 0;    // the camera's own pose flags (pose_decode.h); 0 = usable
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
};

struct FusionResult {
  bool valid = false;  // quorum reached; otherwise position/orientation are the medoid's
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  int present = 0, usable = 0, inliers = 0;
  uint8_t inlier_mask = 0;  // bit i: camera i agreed with the consensus
  // Each usable camera's distance from the fused pose (metres, degrees); NaN
  // for cameras without a usable estimate.
  double deviation_m[kMaxFusedCameras] = {};
  double deviation_deg[kMaxFusedCameras] = {};
  double spread_m = 0, spread_deg = 0;  // RMS deviation of the inliers
};

// @rt. n <= kMaxFusedCameras.
FusionResult fuse_poses(const CameraEstimate* estimates, int n, const FusionParams& p) noexcept;

// A camera's network estimate in base_link, without any map offset (the
// outputs apply that once, to the fused pose). @rt.
CameraEstimate camera_to_base(const PoseEstimate& sensor_in_map,
                              const Eigen::Isometry3d& base_from_sensor) noexcept;

// The fused base_link pose expressed as the pose camera `sensor` would have
// had (T_map_base * T_base_sensor): what the single-camera outputs take. @rt.
PoseEstimate base_to_sensor(const Eigen::Vector3d& position, const Eigen::Quaterniond& orientation,
                            const Eigen::Isometry3d& base_from_sensor) noexcept;

}  // namespace aprt
