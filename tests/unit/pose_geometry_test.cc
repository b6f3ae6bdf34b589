// Sensor pose -> base_link in the ECU's map frame (Eigen).
#include "runtime/pose/pose_geometry.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "runtime/base/allocation_counter.h"

namespace aprt {
namespace {

constexpr double kDeg = M_PI / 180.0;

// The sensor's pose in the map for a vehicle pose and a mounting: T_map_base * T_base_sensor.
PoseEstimate sensor_pose(const RigidTransform& base, const RigidTransform& mount) {
  const Eigen::Isometry3d t = base.isometry() * mount.isometry();
  const Eigen::Quaterniond q(t.linear());
  PoseEstimate p{};
  for (int k = 0; k < 3; ++k) p.position[k] = t.translation()[k];
  p.orientation[0] = q.w();
  p.orientation[1] = q.x();
  p.orientation[2] = q.y();
  p.orientation[3] = q.z();
  return p;
}

RigidTransform make(double x, double y, double z, double roll, double pitch, double yaw) {
  const double xyz[3] = {x, y, z}, rpy[3] = {roll, pitch, yaw};
  return RigidTransform::from_xyz_rpy(xyz, rpy);
}

TEST(PoseGeometry, RpyFollowsRep103) {
  // Yaw 90 deg turns x onto y; pitch +90 turns x onto -z.
  const Eigen::Vector3d x = make(0, 0, 0, 0, 0, 90).rotation * Eigen::Vector3d::UnitX();
  EXPECT_NEAR(x.y(), 1.0, 1e-12);
  const Eigen::Vector3d p = make(0, 0, 0, 0, 90, 0).rotation * Eigen::Vector3d::UnitX();
  EXPECT_NEAR(p.z(), -1.0, 1e-12);
}

TEST(PoseGeometry, IdentityMountingPassesThrough) {
  PoseGeometry g(RigidTransform{}, RigidTransform{}, 1.0, 2.0 * kDeg);
  const PoseEstimate s = sensor_pose(make(10, -20, 0.5, 0, 0, 30), RigidTransform{});
  const BasePose b = g.to_base_link(s);
  EXPECT_NEAR(b.position.x(), 10, 1e-9);
  EXPECT_NEAR(b.position.y(), -20, 1e-9);
  EXPECT_NEAR(b.orientation.angularDistance(make(0, 0, 0, 0, 0, 30).rotation), 0, 1e-9);
}

TEST(PoseGeometry, RemovesTheCameraMountingForRandomPoses) {
  const RigidTransform mount = make(1.2, 0.0, 1.55, 0, 3.0, 0);  // the demo car's camera
  PoseGeometry g(mount, RigidTransform{}, 1.0, 1.0 * kDeg);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> pos(-5000, 5000), ang(-180, 180), tilt(-5, 5);
  for (int i = 0; i < 500; ++i) {
    const RigidTransform base = make(pos(rng), pos(rng), tilt(rng), tilt(rng), tilt(rng), ang(rng));
    const BasePose b = g.to_base_link(sensor_pose(base, mount));
    EXPECT_NEAR((b.position - base.translation).norm(), 0, 1e-6);
    EXPECT_NEAR(b.orientation.angularDistance(base.rotation), 0, 1e-9);
    EXPECT_NEAR(b.orientation.norm(), 1.0, 1e-12);
  }
}

TEST(PoseGeometry, CameraAheadOfTheAxleMovesBaseLinkBack) {
  // Vehicle heading east (yaw 0): base_link is 1.2 m behind and 1.55 m below the camera.
  PoseGeometry g(make(1.2, 0, 1.55, 0, 0, 0), RigidTransform{}, 1, 1);
  PoseEstimate s{};
  s.position[0] = 100;
  s.position[1] = 50;
  s.position[2] = 1.55;
  s.orientation[0] = 1;
  const BasePose b = g.to_base_link(s);
  EXPECT_NEAR(b.position.x(), 98.8, 1e-9);
  EXPECT_NEAR(b.position.y(), 50, 1e-9);
  EXPECT_NEAR(b.position.z(), 0, 1e-9);
}

TEST(PoseGeometry, MapOffsetIsAppliedLast) {
  const RigidTransform offset = make(1000, 2000, 10, 0, 0, 90);
  PoseGeometry g(RigidTransform{}, offset, 1, 1);
  PoseEstimate s{};
  s.position[0] = 5;  // 5 m east in the training map
  s.orientation[0] = 1;
  const BasePose b = g.to_base_link(s);
  EXPECT_NEAR(b.position.x(), 1000, 1e-9);  // rotated 90 deg: 5 m north of the offset
  EXPECT_NEAR(b.position.y(), 2005, 1e-9);
  EXPECT_NEAR(b.position.z(), 10, 1e-9);
  EXPECT_NEAR(b.orientation.angularDistance(offset.rotation), 0, 1e-9);
}

TEST(PoseGeometry, QuaternionsStayContinuousAndUnit) {
  PoseGeometry g(RigidTransform{}, RigidTransform{}, 1, 1);
  double prev[4] = {};
  for (int i = 0; i < 720; ++i) {
    // Yaw sweeping through +-180 and the network's sign flipping at random.
    const double yaw = (i * 1.0 - 360) * kDeg;
    PoseEstimate s{};
    const double sign = (i % 3 == 0) ? -1.0 : 1.0;
    s.orientation[0] = sign * std::cos(yaw / 2) * 1.3;  // not unit: normalised here
    s.orientation[3] = sign * std::sin(yaw / 2) * 1.3;
    const BasePose b = g.to_base_link(s);
    EXPECT_NEAR(b.orientation.norm(), 1.0, 1e-12);
    const double q[4] = {b.orientation.w(), b.orientation.x(), b.orientation.y(),
                         b.orientation.z()};
    if (i > 0) {
      double dot = 0;
      for (int k = 0; k < 4; ++k) dot += q[k] * prev[k];
      EXPECT_GT(dot, 0.99) << i;
    }
    for (int k = 0; k < 4; ++k) prev[k] = q[k];
  }
}

TEST(PoseGeometry, NonFiniteInputDoesNotPoisonContinuity) {
  PoseGeometry g(RigidTransform{}, RigidTransform{}, 1, 1);
  PoseEstimate s{};
  s.orientation[0] = 1;
  g.to_base_link(s);
  PoseEstimate bad{};
  bad.position[0] = std::numeric_limits<double>::quiet_NaN();
  bad.orientation[0] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(g.to_base_link(bad).position.allFinite());
  s.orientation[0] = -1;  // same rotation, other sign: continuity flips it back
  EXPECT_GT(g.to_base_link(s).orientation.w(), 0.0);
}

TEST(PoseGeometry, CovarianceIsTheIsotropicError) {
  PoseGeometry g(make(1, 2, 3, 0, 0, 45), RigidTransform{}, 2.0, 3.0 * kDeg);
  PoseEstimate s{};
  s.orientation[0] = 1;
  const BasePose b = g.to_base_link(s);
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) {
      const double expect = r != c ? 0.0 : r < 3 ? 4.0 : (3.0 * kDeg) * (3.0 * kDeg);
      EXPECT_DOUBLE_EQ(b.covariance[r * 6 + c], expect);
    }
  }
}

TEST(PoseGeometry, AllocatesNothing) {
  PoseGeometry g(make(1.2, 0, 1.55, 0, 3, 0), make(10, 20, 0, 0, 0, 5), 1, 1);
  PoseEstimate s{};
  s.orientation[0] = 1;
  AllocationScope scope;
  for (int i = 0; i < 100; ++i) {
    s.position[0] = i;
    (void)g.to_base_link(s);
  }
  EXPECT_EQ(scope.count(), 0u);
}

}  // namespace
}  // namespace aprt
