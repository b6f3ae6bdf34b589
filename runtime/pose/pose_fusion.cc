#include "runtime/pose/pose_fusion.h"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>

namespace aprt {
namespace {

double angle_between(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  const double d = std::min(1.0, std::fabs(a.dot(b)));
  return 2.0 * std::acos(d);
}

}  // namespace

CameraEstimate camera_to_base(const PoseEstimate& s,
                              const Eigen::Isometry3d& base_from_sensor) noexcept {
  CameraEstimate e;
  e.present = true;
  e.flags = s.flags;
  Eigen::Quaterniond q(s.orientation[0], s.orientation[1], s.orientation[2], s.orientation[3]);
  if (!(s.flags & (kPoseNonFinite | kPoseQuatDegenerate))) q.normalize();
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = q.toRotationMatrix();
  t.translation() = Eigen::Vector3d(s.position[0], s.position[1], s.position[2]);
  const Eigen::Isometry3d base = t * base_from_sensor.inverse();
  e.position = base.translation();
  e.orientation = Eigen::Quaterniond(base.linear());
  e.orientation.normalize();
  if (!e.position.allFinite() || !e.orientation.coeffs().allFinite()) e.flags |= kPoseNonFinite;
  return e;
}

PoseEstimate base_to_sensor(const Eigen::Vector3d& position, const Eigen::Quaterniond& orientation,
                            const Eigen::Isometry3d& base_from_sensor) noexcept {
  Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
  base.linear() = orientation.normalized().toRotationMatrix();
  base.translation() = position;
  const Eigen::Isometry3d sensor = base * base_from_sensor;
  Eigen::Quaterniond q(sensor.linear());
  q.normalize();
  if (q.w() < 0) q.coeffs() = -q.coeffs();  // pose_decode's convention: w >= 0
  PoseEstimate out;
  for (int k = 0; k < 3; ++k) out.position[k] = sensor.translation()[k];
  out.orientation[0] = q.w();
  out.orientation[1] = q.x();
  out.orientation[2] = q.y();
  out.orientation[3] = q.z();
  out.raw_quat_norm = 1.0f;
  return out;
}

FusionResult fuse_poses(const CameraEstimate* e, int n, const FusionParams& p) noexcept {
  FusionResult r;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  bool usable[kMaxFusedCameras] = {};
  n = std::min(n, kMaxFusedCameras);
  for (int i = 0; i < n; ++i) {
    r.deviation_m[i] = r.deviation_deg[i] = nan;
    r.present += e[i].present ? 1 : 0;
    usable[i] = e[i].present && e[i].flags == 0;
    r.usable += usable[i] ? 1 : 0;
  }
  if (r.usable == 0) return r;

  // The medoid, distances in units of the thresholds.
  int medoid = -1;
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < n; ++i) {
    if (!usable[i]) continue;
    double sum = 0;
    for (int j = 0; j < n; ++j) {
      if (!usable[j] || j == i) continue;
      sum += (e[i].position - e[j].position).norm() / p.max_position_spread_m +
             angle_between(e[i].orientation, e[j].orientation) / p.max_orientation_spread_rad;
    }
    if (sum < best) {
      best = sum;
      medoid = i;
    }
  }

  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  Eigen::Matrix4d m = Eigen::Matrix4d::Zero();
  for (int i = 0; i < n; ++i) {
    if (!usable[i]) continue;
    const bool in =
        (e[i].position - e[medoid].position).norm() <= p.max_position_spread_m &&
        angle_between(e[i].orientation, e[medoid].orientation) <= p.max_orientation_spread_rad;
    if (!in) continue;
    ++r.inliers;
    r.inlier_mask = uint8_t(r.inlier_mask | (1u << i));
    mean += e[i].position;
    const Eigen::Vector4d q = e[i].orientation.coeffs();  // x y z w
    m += q * q.transpose();
  }
  const int quorum = std::max(p.min_agreeing, r.usable / 2 + 1);
  r.valid = r.inliers >= quorum;
  if (r.valid) {
    r.position = mean / double(r.inliers);
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eig(m);
    const Eigen::Vector4d v = eig.eigenvectors().col(3);  // largest eigenvalue (ascending order)
    r.orientation = Eigen::Quaterniond(v[3], v[0], v[1], v[2]);
    r.orientation.normalize();
    if (r.orientation.dot(e[medoid].orientation) < 0) r.orientation.coeffs() *= -1.0;
  } else {
    r.position = e[medoid].position;
    r.orientation = e[medoid].orientation;
  }
  double sp = 0, sa = 0;
  for (int i = 0; i < n; ++i) {
    if (!usable[i]) continue;
    r.deviation_m[i] = (e[i].position - r.position).norm();
    r.deviation_deg[i] = angle_between(e[i].orientation, r.orientation) * 180.0 / M_PI;
    if (r.inlier_mask & (1u << i)) {
      sp += r.deviation_m[i] * r.deviation_m[i];
      sa += r.deviation_deg[i] * r.deviation_deg[i];
    }
  }
  if (r.inliers > 0) {
    r.spread_m = std::sqrt(sp / r.inliers);
    r.spread_deg = std::sqrt(sa / r.inliers);
  }
  return r;
}

}  // namespace aprt
