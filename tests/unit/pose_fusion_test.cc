// Multi-camera fusion (runtime/pose/pose_fusion.h) on a rig like upstream's:
// front-centre, front-left and front-right cameras, the side ones turned by
// +-60 degrees of yaw, each estimating its own pose in the map.
#include "runtime/pose/pose_fusion.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace aprt {
namespace {

constexpr double kDeg = M_PI / 180.0;

Eigen::Isometry3d mount(double x, double y, double z, double yaw_deg) {
  const double xyz[3] = {x, y, z}, rpy[3] = {0, 2.0, yaw_deg};
  return RigidTransform::from_xyz_rpy(xyz, rpy).isometry();
}

struct Rig {
  Eigen::Isometry3d cams[3] = {mount(1.5, 0, 1.6, 0), mount(1.3, 0.6, 1.6, 60),
                               mount(1.3, -0.6, 1.6, -60)};
};

Eigen::Isometry3d vehicle(double x, double y, double yaw_deg) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::AngleAxisd(yaw_deg * kDeg, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  t.translation() = Eigen::Vector3d(x, y, 0.1);
  return t;
}

// What the network would say for camera `mount` on a vehicle at `base`, with
// an error of `dx` metres and `dyaw` degrees.
PoseEstimate network_says(const Eigen::Isometry3d& base, const Eigen::Isometry3d& mount_,
                          double dx = 0, double dyaw = 0) {
  Eigen::Isometry3d s = base * mount_;
  s.translation().x() += dx;
  s.linear() =
      Eigen::AngleAxisd(dyaw * kDeg, Eigen::Vector3d::UnitZ()).toRotationMatrix() * s.linear();
  const Eigen::Quaterniond q(s.linear());
  PoseEstimate p;
  for (int k = 0; k < 3; ++k) p.position[k] = s.translation()[k];
  p.orientation[0] = q.w();
  p.orientation[1] = q.x();
  p.orientation[2] = q.y();
  p.orientation[3] = q.z();
  return p;
}

double yaw_error_deg(const Eigen::Quaterniond& q, const Eigen::Isometry3d& truth) {
  return q.angularDistance(Eigen::Quaterniond(truth.linear())) / kDeg;
}

TEST(PoseFusion, SideCamerasBroughtToBaseLinkAgreeWithTheFrontOne) {
  const Rig rig;
  const Eigen::Isometry3d base = vehicle(120.0, -43.0, 35.0);
  CameraEstimate e[3];
  for (int i = 0; i < 3; ++i) e[i] = camera_to_base(network_says(base, rig.cams[i]), rig.cams[i]);
  const FusionResult r = fuse_poses(e, 3, FusionParams{});
  ASSERT_TRUE(r.valid);
  EXPECT_EQ(r.inliers, 3);
  EXPECT_EQ(r.inlier_mask, 0b111);
  EXPECT_LT((r.position - base.translation()).norm(), 1e-9);
  EXPECT_LT(yaw_error_deg(r.orientation, base), 1e-7);
  EXPECT_LT(r.spread_m, 1e-9);
}

TEST(PoseFusion, NoisyEstimatesAverageAndTheOutlierIsRejected) {
  const Rig rig;
  const Eigen::Isometry3d base = vehicle(10.0, 5.0, -170.0);
  CameraEstimate e[3];
  e[0] = camera_to_base(network_says(base, rig.cams[0], 0.8, 2.0), rig.cams[0]);
  e[1] = camera_to_base(network_says(base, rig.cams[1], -0.8, -2.0), rig.cams[1]);
  e[2] = camera_to_base(network_says(base, rig.cams[2], 40.0, 0.0), rig.cams[2]);  // wild
  const FusionResult r = fuse_poses(e, 3, FusionParams{});
  ASSERT_TRUE(r.valid);
  EXPECT_EQ(r.inliers, 2);
  EXPECT_EQ(r.inlier_mask, 0b011);
  // The two errors cancel: the mean of the inliers.
  EXPECT_LT((r.position - base.translation()).norm(), 0.05);
  EXPECT_LT(yaw_error_deg(r.orientation, base), 0.05);
  EXPECT_GT(r.deviation_m[2], 35.0);
  EXPECT_NEAR(r.spread_deg, 2.0, 0.1);
}

TEST(PoseFusion, AnOrientationOutlierIsRejectedToo) {
  const Rig rig;
  const Eigen::Isometry3d base = vehicle(0, 0, 90.0);
  CameraEstimate e[3];
  for (int i = 0; i < 3; ++i) e[i] = camera_to_base(network_says(base, rig.cams[i]), rig.cams[i]);
  e[0] = camera_to_base(network_says(base, rig.cams[0], 0, 45.0), rig.cams[0]);
  FusionParams p;
  p.max_position_spread_m = 1e4;  // only orientation decides here
  const FusionResult r = fuse_poses(e, 3, p);
  ASSERT_TRUE(r.valid);
  EXPECT_EQ(r.inlier_mask, 0b110);
  EXPECT_NEAR(r.deviation_deg[0], 45.0, 1e-6);
}

TEST(PoseFusion, TwoCamerasThatDisagreeHaveNoQuorum) {
  const Rig rig;
  const Eigen::Isometry3d base = vehicle(3, 4, 0);
  CameraEstimate e[2] = {camera_to_base(network_says(base, rig.cams[0]), rig.cams[0]),
                         camera_to_base(network_says(base, rig.cams[1], 20.0), rig.cams[1])};
  const FusionResult r = fuse_poses(e, 2, FusionParams{});
  EXPECT_FALSE(r.valid);
  EXPECT_EQ(r.usable, 2);
  EXPECT_EQ(r.inliers, 1);
}

TEST(PoseFusion, FlaggedAndMissingCamerasDoNotVote) {
  const Rig rig;
  const Eigen::Isometry3d base = vehicle(3, 4, 10);
  CameraEstimate e[3];
  e[0] = camera_to_base(network_says(base, rig.cams[0]), rig.cams[0]);
  PoseEstimate bad = network_says(base, rig.cams[1], 500.0);
  bad.flags = kPoseOutOfBounds;
  e[1] = camera_to_base(bad, rig.cams[1]);
  // e[2]: no frame this cycle.
  FusionResult r = fuse_poses(e, 3, FusionParams{});
  EXPECT_TRUE(r.valid);  // one usable estimate is its own majority
  EXPECT_EQ(r.present, 2);
  EXPECT_EQ(r.usable, 1);
  EXPECT_TRUE(std::isnan(r.deviation_m[1]));
  EXPECT_TRUE(std::isnan(r.deviation_m[2]));
  FusionParams two;
  two.min_agreeing = 2;  // ... unless the configuration wants two
  r = fuse_poses(e, 3, two);
  EXPECT_FALSE(r.valid);
  CameraEstimate none[2];
  EXPECT_FALSE(fuse_poses(none, 2, FusionParams{}).valid);
}

TEST(PoseFusion, NonFiniteNetworkOutputIsNotUsable) {
  const Rig rig;
  PoseEstimate p = network_says(vehicle(0, 0, 0), rig.cams[0]);
  p.position[1] = std::nan("");
  const CameraEstimate e = camera_to_base(p, rig.cams[0]);
  EXPECT_NE(e.flags & kPoseNonFinite, 0u);
}

TEST(PoseFusion, QuaternionSignsDoNotMatter) {
  // q and -q are one rotation: averaging them must not cancel out.
  const Eigen::Isometry3d base = vehicle(0, 0, 135.0);
  CameraEstimate e[3];
  for (int i = 0; i < 3; ++i) {
    e[i].present = true;
    e[i].position = base.translation();
    e[i].orientation = Eigen::Quaterniond(base.linear());
  }
  e[1].orientation.coeffs() *= -1.0;
  const FusionResult r = fuse_poses(e, 3, FusionParams{});
  ASSERT_TRUE(r.valid);
  EXPECT_EQ(r.inliers, 3);
  EXPECT_LT(yaw_error_deg(r.orientation, base), 1e-7);
}

TEST(PoseFusion, RandomRigsRoundTrip) {
  // base -> each camera's estimate -> fused base -> the trigger camera's pose
  // (what the outputs take) -> base again, with random mountings and poses.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Isometry3d base = vehicle(500 * u(rng), 500 * u(rng), 180 * u(rng));
    Eigen::Isometry3d m[4];
    CameraEstimate e[4];
    for (int i = 0; i < 4; ++i) {
      m[i] = mount(2 * u(rng), u(rng), 1.5 + 0.3 * u(rng), 180 * u(rng));
      e[i] = camera_to_base(network_says(base, m[i]), m[i]);
    }
    const FusionResult r = fuse_poses(e, 4, FusionParams{});
    ASSERT_TRUE(r.valid);
    const PoseEstimate s = base_to_sensor(r.position, r.orientation, m[0]);
    EXPECT_GE(s.orientation[0], 0.0);
    const CameraEstimate back = camera_to_base(s, m[0]);
    EXPECT_LT((back.position - base.translation()).norm(), 1e-6);
    EXPECT_LT(yaw_error_deg(back.orientation, base), 1e-6);
  }
}

}  // namespace
}  // namespace aprt
