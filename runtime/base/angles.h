#pragma once
// Yaw and angle differences, shared by the validity gate, the fusion of two
// sensors, the console and the decoders: one formula, one wrap convention.

#include <cmath>

namespace aprt {

inline constexpr double kPiRad = 3.14159265358979323846;

// The yaw (rad) of the quaternion w x y z about the map's z axis.
inline double yaw_of_quaternion(double w, double x, double y, double z) noexcept {
  return std::atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z));
}

// The same for a w x y z array (the layout of PoseEstimate::orientation).
inline double quaternion_yaw(const double q[4]) noexcept {
  return yaw_of_quaternion(q[0], q[1], q[2], q[3]);
}

// An angle (rad) brought into [-pi, pi]: the signed difference of two headings.
inline double wrap_angle(double a) noexcept {
  return std::remainder(a, 2 * kPiRad);
}

}  // namespace aprt
