// From the network's sensor pose to what the localisation ECU wants: the
// vehicle's base_link in the ECU's map frame (Eigen; never on a kernel).
//
//   T_map_base = T_offset * T_model_sensor * T_base_sensor^-1
//
// T_model_sensor is the estimate (the frame the network was trained on, in
// the training map frame), T_base_sensor the sensor's mounting on the vehicle
// (extrinsic), T_offset an optional transform from the training map frame to
// the ECU's. Quaternions stay unit length and continuous (the sign that is
// closest to the previous output). The covariance is the model's own for the
// frame where the model file has confidence outputs (FORMAT.md 1.3);
// otherwise its isotropic validation error (or the configuration's).
#pragma once

#include <Eigen/Geometry>

#include "runtime/engine/pose_decode.h"

namespace aprt {

struct RigidTransform {
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();

  // roll, pitch, yaw in degrees (Z-Y-X intrinsic, REP 103).
  static RigidTransform from_xyz_rpy(const double xyz[3], const double rpy_deg[3]);
  Eigen::Isometry3d isometry() const;
};

struct BasePose {
  Eigen::Vector3d position;
  Eigen::Quaterniond orientation;  // unit
  double covariance[36];           // row-major: x y z, rotation about x y z (ROS convention)
};

class PoseGeometry {
 public:
  PoseGeometry(const RigidTransform& sensor_on_base, const RigidTransform& map_offset,
               double sigma_position_m, double sigma_orientation_rad);

  // @rt (Eigen fixed-size types only: no allocation).
  BasePose to_base_link(const PoseEstimate& sensor_in_map) noexcept;
  // The same from base_link already in the training map frame (the loop's
  // estimate: the extrinsic applied once, where cameras are fused): only the
  // map offset, continuity and covariance. @rt.
  BasePose from_base(const double position[3], const double orientation[4]) noexcept;
  // The covariance of one estimate from the model's own confidence
  // (sensor.has_sigma): the position's per-axis variances rotated by the map
  // offset, the rotation's (about the camera's axes) into the ECU's map frame
  // -- ROS's fixed-axis convention. The constant validation error otherwise.
  // @rt.
  void covariance(const PoseEstimate& sensor, double out[36]) const noexcept;
  void reset_continuity() { have_previous_ = false; }

 private:
  BasePose finish(const Eigen::Isometry3d& base_in_map) noexcept;
  Eigen::Isometry3d base_from_sensor_inv_;  // T_base_sensor^-1 = T_sensor_base
  Eigen::Isometry3d offset_;
  double var_pos_, var_rot_;
  Eigen::Quaterniond previous_;
  bool have_previous_ = false;
};

}  // namespace aprt
