// The pose filter (pose_filter.h) between the model's estimates and what goes
// out: the sensor's estimate in (converted to base_link, the frame the
// vehicle's odometry moves), the published pose out -- base_link with the
// filter's x, y and yaw (height, roll and pitch from the latest usable
// estimate), the same as the sensor's pose for the console and the errors,
// with the filter's standard deviations as the pose's confidence.
//
// An estimate is a measurement when nothing flagged it and the model's own
// 95 % regions are within the filter's EstimateLimits (sanity.filter's
// estimate_max_radius_m, estimate_max_yaw_deg): the others move nothing. @rt after
// construction: no allocation.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>

#include "drivers/input/odometry.h"
#include "runtime/engine/pose_decode.h"
#include "runtime/pose/pose_filter.h"

namespace aprt {

struct FilteredPose {
  PoseEstimate sensor;  // what goes out, as the sensor's pose (console, errors, covariance)
  double base_position[3] = {};
  double base_orientation[4] = {1, 0, 0, 0};  // w x y z
  uint32_t flags = 0;                      // the filter's (0: valid) | the estimate's before a fix
  bool fix = false;                        // the filter has a pose (else: the estimate)
  double radius95_m = -1, yaw95_deg = -1;  // its published 95 % regions (-1: no fix)
  PoseFilter::Use use = PoseFilter::Use::kNone;
  int refused = 0;
};

struct OdometryFilterParams : EstimateLimits {
  PoseFilterParams filter;
  double fallback_sigma_m = 5.0;  // for a model without confidence outputs
  double fallback_sigma_rad = 0.05;
};

class OdometryFilter {
 public:
  OdometryFilter(const OdometryFilterParams& p, const Eigen::Isometry3d& base_from_sensor);

  // One frame: the sensor's estimate, every flag it has so far (any flag:
  // not a measurement), and base_link's motion since the previous frame
  // (null: unknown). @rt.
  FilteredPose step(const PoseEstimate& sensor, uint32_t flags,
                    const PlanarMotion* motion) noexcept;
  void reset() noexcept;
  // Off: the estimator's validity gate decides alone (no odometry).
  bool enabled() const { return p_.filter.enabled; }

 private:
  OdometryFilterParams p_;
  PoseFilter filter_;
  Eigen::Isometry3d base_from_sensor_;
  // The latest usable estimate's height, roll and pitch (base_link) and the
  // sensor's standard deviations the filter does not estimate.
  bool have_attitude_ = false;
  Eigen::Quaterniond attitude_ = Eigen::Quaterniond::Identity();
  double z_ = 0, sigma_z_ = 0, sigma_roll_ = 0, sigma_pitch_ = 0;
};

}  // namespace aprt
