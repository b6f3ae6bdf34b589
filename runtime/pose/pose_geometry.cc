#include "runtime/pose/pose_geometry.h"

#include <cmath>

namespace aprt {

RigidTransform RigidTransform::from_xyz_rpy(const double xyz[3], const double rpy_deg[3]) {
  RigidTransform t;
  t.translation = Eigen::Vector3d(xyz[0], xyz[1], xyz[2]);
  const double k = M_PI / 180.0;
  t.rotation = Eigen::AngleAxisd(rpy_deg[2] * k, Eigen::Vector3d::UnitZ()) *
               Eigen::AngleAxisd(rpy_deg[1] * k, Eigen::Vector3d::UnitY()) *
               Eigen::AngleAxisd(rpy_deg[0] * k, Eigen::Vector3d::UnitX());
  t.rotation.normalize();
  return t;
}

Eigen::Isometry3d RigidTransform::isometry() const {
  Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
  m.linear() = rotation.toRotationMatrix();
  m.translation() = translation;
  return m;
}

PoseGeometry::PoseGeometry(const RigidTransform& sensor_on_base, const RigidTransform& map_offset,
                           double sigma_position_m, double sigma_orientation_rad)
    : base_from_sensor_inv_(sensor_on_base.isometry().inverse()),
      offset_(map_offset.isometry()),
      var_pos_(sigma_position_m * sigma_position_m),
      var_rot_(sigma_orientation_rad * sigma_orientation_rad) {}

BasePose PoseGeometry::to_base_link(const PoseEstimate& s) noexcept {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  Eigen::Quaterniond q(s.orientation[0], s.orientation[1], s.orientation[2], s.orientation[3]);
  q.normalize();
  t.linear() = q.toRotationMatrix();
  t.translation() = Eigen::Vector3d(s.position[0], s.position[1], s.position[2]);
  return finish(t * base_from_sensor_inv_);
}

BasePose PoseGeometry::from_base(const double position[3], const double orientation[4]) noexcept {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  Eigen::Quaterniond q(orientation[0], orientation[1], orientation[2], orientation[3]);
  q.normalize();
  t.linear() = q.toRotationMatrix();
  t.translation() = Eigen::Vector3d(position[0], position[1], position[2]);
  return finish(t);
}

void PoseGeometry::covariance(const PoseEstimate& s, double out[36]) const noexcept {
  for (int i = 0; i < 36; ++i) out[i] = 0.0;
  if (!s.has_sigma) {
    for (int i = 0; i < 3; ++i) {
      out[i * 6 + i] = var_pos_;
      out[(i + 3) * 6 + (i + 3)] = var_rot_;
    }
    return;
  }
  const Eigen::Matrix3d off = offset_.linear();
  const Eigen::Vector3d sp(s.sigma_position_m[0], s.sigma_position_m[1], s.sigma_position_m[2]);
  const Eigen::Matrix3d pos = off * sp.cwiseProduct(sp).asDiagonal() * off.transpose();
  Eigen::Quaterniond q(s.orientation[0], s.orientation[1], s.orientation[2], s.orientation[3]);
  q.normalize();
  const Eigen::Matrix3d map_from_camera = off * q.toRotationMatrix();
  const Eigen::Vector3d sr(s.sigma_rotation_rad[0], s.sigma_rotation_rad[1],
                           s.sigma_rotation_rad[2]);
  const Eigen::Matrix3d rot =
      map_from_camera * sr.cwiseProduct(sr).asDiagonal() * map_from_camera.transpose();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      out[r * 6 + c] = pos(r, c);
      out[(r + 3) * 6 + (c + 3)] = rot(r, c);
    }
  }
}

BasePose PoseGeometry::finish(const Eigen::Isometry3d& base_in_map) noexcept {
  const Eigen::Isometry3d base = offset_ * base_in_map;
  BasePose out;
  out.position = base.translation();
  Eigen::Quaterniond r(base.linear());
  r.normalize();
  if (r.coeffs().allFinite() && out.position.allFinite()) {
    if (have_previous_ && r.dot(previous_) < 0) r.coeffs() = -r.coeffs();  // continuity
    previous_ = r;
    have_previous_ = true;
  }
  out.orientation = r;
  // The model's error is isotropic: the same diagonal in any frame.
  for (int i = 0; i < 36; ++i) out.covariance[i] = 0.0;
  for (int i = 0; i < 3; ++i) {
    out.covariance[i * 6 + i] = var_pos_;
    out.covariance[(i + 3) * 6 + (i + 3)] = var_rot_;
  }
  return out;
}

}  // namespace aprt
