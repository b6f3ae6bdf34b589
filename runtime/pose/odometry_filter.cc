#include "runtime/pose/odometry_filter.h"

#include <cmath>

#include "runtime/base/angles.h"
#include "runtime/pose/pose_flags.h"
#include "runtime/pose/pose_fusion.h"
#include "runtime/pose/pose_gate.h"

namespace aprt {
namespace {

double yaw_of(const Eigen::Quaterniond& q) {
  return yaw_of_quaternion(q.w(), q.x(), q.y(), q.z());
}

}  // namespace

OdometryFilter::OdometryFilter(const OdometryFilterParams& p,
                               const Eigen::Isometry3d& base_from_sensor)
    : p_(p), filter_(p.filter), base_from_sensor_(base_from_sensor) {}

void OdometryFilter::reset() noexcept {
  filter_.reset();
  have_attitude_ = false;
}

FilteredPose OdometryFilter::step(const PoseEstimate& sensor, uint32_t flags,
                                  const PlanarMotion* motion) noexcept {
  const CameraEstimate base = camera_to_base(sensor, base_from_sensor_);
  const bool usable = flags == 0 && base.flags == 0 &&
                      confident(sensor, p_.estimate_max_radius_m, p_.estimate_max_yaw_deg);
  PlanarPose z;
  if (usable) {
    z.x = base.position.x();
    z.y = base.position.y();
    z.yaw = yaw_of(base.orientation);
    z.sigma_x = sensor.has_sigma ? sensor.sigma_position_m[0] : p_.fallback_sigma_m;
    z.sigma_y = sensor.has_sigma ? sensor.sigma_position_m[1] : p_.fallback_sigma_m;
    z.sigma_yaw = sensor.has_sigma ? sensor.sigma_rotation_rad[2] : p_.fallback_sigma_rad;
    attitude_ = base.orientation;
    z_ = base.position.z();
    sigma_z_ = sensor.has_sigma ? sensor.sigma_position_m[2] : p_.fallback_sigma_m;
    sigma_roll_ = sensor.has_sigma ? sensor.sigma_rotation_rad[0] : p_.fallback_sigma_rad;
    sigma_pitch_ = sensor.has_sigma ? sensor.sigma_rotation_rad[1] : p_.fallback_sigma_rad;
    have_attitude_ = true;
  }
  if (!motion) have_attitude_ = usable;  // nothing older carries over
  const PoseFilter::Output o = filter_.step(motion, usable ? &z : nullptr);
  FilteredPose out;
  out.use = o.use;
  out.refused = o.refused;
  out.fix = o.fix && have_attitude_;
  if (out.fix) {
    out.radius95_m = o.radius95_m;
    out.yaw95_deg = o.yaw95_deg;
  }
  if (!o.fix || !have_attitude_) {
    // No fix yet: the estimate as it is, never valid.
    out.sensor = sensor;
    for (int k = 0; k < 3; ++k) out.base_position[k] = base.position[k];
    out.base_orientation[0] = base.orientation.w();
    out.base_orientation[1] = base.orientation.x();
    out.base_orientation[2] = base.orientation.y();
    out.base_orientation[3] = base.orientation.z();
    out.flags = o.flags | kPoseUnconfirmed;
    return out;
  }
  // The latest usable estimate's attitude turned to the filter's yaw.
  const Eigen::Quaterniond turn(
      Eigen::AngleAxisd(wrap_angle(o.pose.yaw - yaw_of(attitude_)), Eigen::Vector3d::UnitZ()));
  const Eigen::Quaterniond q = (turn * attitude_).normalized();
  const Eigen::Vector3d position(o.pose.x, o.pose.y, z_);
  out.sensor = base_to_sensor(position, q, base_from_sensor_);
  out.sensor.has_sigma = true;
  out.sensor.sigma_position_m[0] = o.pose.sigma_x;
  out.sensor.sigma_position_m[1] = o.pose.sigma_y;
  out.sensor.sigma_position_m[2] = sigma_z_;
  out.sensor.sigma_rotation_rad[0] = sigma_roll_;
  out.sensor.sigma_rotation_rad[1] = sigma_pitch_;
  out.sensor.sigma_rotation_rad[2] = o.pose.sigma_yaw;
  for (int k = 0; k < 3; ++k) out.base_position[k] = position[k];
  out.base_orientation[0] = q.w();
  out.base_orientation[1] = q.x();
  out.base_orientation[2] = q.y();
  out.base_orientation[3] = q.z();
  out.flags = o.flags;
  return out;
}

}  // namespace aprt
