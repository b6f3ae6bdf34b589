// Two sensors' estimates combined (runtime/pose/sensor_fusion.h): one valid
// goes out alone, two that agree give their inverse-variance mean, two that
// disagree go to the longer valid history or to neither, and nothing valid
// shows the estimate with the smaller stated variance, flagged. And the
// companion's estimate moved onto another time by its track (PoseGate::motion).
#include "runtime/pose/sensor_fusion.h"

#include <gtest/gtest.h>

#include <cmath>

#include "runtime/base/allocation_counter.h"
#include "runtime/pose/pose_flags.h"
#include "runtime/pose/pose_gate.h"

namespace aprt {
namespace {

SensorEstimate at(double x, double y, double yaw_deg, double var, double var_yaw = 1e-3) {
  SensorEstimate e;
  e.present = true;
  e.position = Eigen::Vector3d(x, y, 0.0);
  e.orientation =
      Eigen::Quaterniond(Eigen::AngleAxisd(yaw_deg * M_PI / 180, Eigen::Vector3d::UnitZ()));
  for (double& v : e.var_position) v = var;
  e.var_yaw = var_yaw;
  return e;
}

double yaw_deg(const Eigen::Quaterniond& q) {
  return std::atan2(2 * (q.w() * q.z() + q.x() * q.y()), 1 - 2 * (q.y() * q.y() + q.z() * q.z())) *
         180 / M_PI;
}

TEST(SensorFusion, OneValidGoesOutAlone) {
  SensorEstimate a = at(10, 20, 30, 4), b = at(11, 20, 31, 1);
  b.flags = kPoseUnconfirmed;
  SensorFusionResult r = fuse_sensors(a, b, {});
  EXPECT_EQ(r.from, FusedFrom::kPrimary);
  EXPECT_EQ(r.pose.flags, 0u);
  EXPECT_EQ(r.pose.position, a.position);
  a.flags = kPoseUncertain;
  b.flags = 0;
  r = fuse_sensors(a, b, {});
  EXPECT_EQ(r.from, FusedFrom::kCompanion);
  EXPECT_EQ(r.pose.flags, 0u);
  EXPECT_EQ(r.pose.position, b.position);
  // A companion without a recent estimate leaves the run's own.
  a.flags = 0;
  b.present = false;
  r = fuse_sensors(a, b, {});
  EXPECT_EQ(r.from, FusedFrom::kPrimary);
  EXPECT_LT(r.distance_m, 0);
}

TEST(SensorFusion, TwoThatAgreeGiveTheirInverseVarianceMean) {
  const SensorEstimate a = at(10, 20, 30, 4.0, 4e-3), b = at(12, 21, 34, 1.0, 1e-3);
  const SensorFusionResult r = fuse_sensors(a, b, {});
  EXPECT_EQ(r.from, FusedFrom::kBoth);
  EXPECT_EQ(r.pose.flags, 0u);
  // b has a quarter of a's variance: 4/5 of the way from a to b.
  EXPECT_NEAR(r.pose.position.x(), 10 + 0.8 * 2, 1e-9);
  EXPECT_NEAR(r.pose.position.y(), 20 + 0.8 * 1, 1e-9);
  EXPECT_NEAR(r.pose.var_position[0], 0.8, 1e-9);  // 4 * 1 / (4 + 1)
  EXPECT_NEAR(yaw_deg(r.pose.orientation), 30 + 0.8 * 4, 1e-6);
  EXPECT_NEAR(r.pose.var_yaw, 0.8e-3, 1e-12);
  EXPECT_NEAR(r.distance_m, std::hypot(2.0, 1.0), 1e-9);
  EXPECT_NEAR(r.yaw_diff_rad * 180 / M_PI, 4, 1e-6);
  EXPECT_FALSE(r.disagree);
}

TEST(SensorFusion, YawAveragedAcrossTheWrap) {
  const SensorEstimate a = at(0, 0, 179, 1, 1e-3), b = at(0, 0, -179, 1, 1e-3);
  const SensorFusionResult r = fuse_sensors(a, b, {});
  EXPECT_EQ(r.from, FusedFrom::kBoth);
  EXPECT_NEAR(std::fabs(yaw_deg(r.pose.orientation)), 180, 1e-6);
}

TEST(SensorFusion, ADisagreementGoesToTheLongerValidHistoryOrToNeither) {
  SensorFusionParams p;
  p.max_position_spread_m = 5;
  p.min_lead_s = 1.0;
  SensorEstimate a = at(10, 20, 30, 1), b = at(10, 40, 30, 1);  // 20 m apart
  a.valid_for_s = 5.0;
  b.valid_for_s = 0.5;
  SensorFusionResult r = fuse_sensors(a, b, p);
  EXPECT_TRUE(r.disagree);
  EXPECT_EQ(r.from, FusedFrom::kPrimary);
  EXPECT_EQ(r.pose.flags, 0u);
  a.valid_for_s = 0.2;
  r = fuse_sensors(a, b, p);
  EXPECT_EQ(r.from, FusedFrom::kPrimary);  // shown, withheld
  EXPECT_EQ(r.pose.flags, kPoseNoQuorum);
  b.valid_for_s = 1.3;
  r = fuse_sensors(a, b, p);
  EXPECT_EQ(r.from, FusedFrom::kCompanion);
  EXPECT_EQ(r.pose.flags, 0u);
  EXPECT_EQ(r.pose.position, b.position);
  // A yaw disagreement is one too.
  b = at(10, 20, 60, 1);
  r = fuse_sensors(a, b, p);
  EXPECT_TRUE(r.disagree);
}

TEST(SensorFusion, CrossCheckHoldsBackAFreshValidEstimateTheOtherContradicts) {
  SensorFusionParams p;
  SensorEstimate a = at(10, 20, 30, 1), b = at(10, 40, 30, 1);  // 20 m apart
  b.flags = kPoseUnconfirmed;                                   // a real estimate, not (yet) valid
  a.valid_for_s = 0.3;
  EXPECT_EQ(fuse_sensors(a, b, p).pose.flags, 0u);  // off by default
  p.cross_check = true;
  SensorFusionResult r = fuse_sensors(a, b, p);
  EXPECT_EQ(r.from, FusedFrom::kPrimary);
  EXPECT_EQ(r.pose.flags, kPoseNoQuorum);
  a.valid_for_s = 1.5;  // a history of its own: the other's unconfirmed estimate does not stop it
  EXPECT_EQ(fuse_sensors(a, b, p).pose.flags, 0u);
  a.valid_for_s = 0.3;
  b.flags = kPoseOutOfBounds;  // no real estimate: nothing to contradict
  EXPECT_EQ(fuse_sensors(a, b, p).pose.flags, 0u);
  b = at(11, 20, 31, 1);  // agreeing
  b.flags = kPoseUncertain;
  EXPECT_EQ(fuse_sensors(a, b, p).pose.flags, 0u);
}

TEST(SensorFusion, NothingValidShowsTheSmallerStatedVarianceFlagged) {
  SensorEstimate a = at(10, 20, 30, 400), b = at(12, 20, 30, 2);
  a.flags = kPoseUncertain;
  b.flags = kPoseUnconfirmed;
  SensorFusionResult r = fuse_sensors(a, b, {});
  EXPECT_EQ(r.from, FusedFrom::kCompanion);
  EXPECT_EQ(r.pose.flags, kPoseUnconfirmed);
  b.var_position[1] = 900;
  r = fuse_sensors(a, b, {});
  EXPECT_EQ(r.from, FusedFrom::kPrimary);
  EXPECT_EQ(r.pose.flags, kPoseUncertain);
}

TEST(SensorFusion, AllocatesNothing) {
  const SensorEstimate a = at(10, 20, 30, 4), b = at(12, 21, 34, 1);
  volatile double sink = 0;
  const uint64_t before = allocation_count();
  for (int i = 0; i < 1000; ++i) sink = sink + fuse_sensors(a, b, {}).pose.position.x();
  EXPECT_EQ(allocation_count(), before);
}

TEST(ValidStreak, CountsFromTheFirstValidAndRestartsAfterABreak) {
  ValidStreak s;
  EXPECT_EQ(s.update(true, 10.0), 0.0);
  EXPECT_DOUBLE_EQ(s.update(true, 12.5), 2.5);
  EXPECT_EQ(s.update(false, 13.0), 0.0);
  EXPECT_EQ(s.update(true, 14.0), 0.0);
  EXPECT_DOUBLE_EQ(s.update(true, 14.25), 0.25);
}

TEST(PoseGateMotion, TheConfirmedTracksMotionBetweenTwoTimes) {
  PoseGateParams params;
  params.confirm = 4;
  PoseGate g(params);
  double dx, dy, dyaw;
  EXPECT_FALSE(g.motion(0, 0.1, &dx, &dy, &dyaw));  // no track: nothing to move by
  EXPECT_EQ(dx, 0.0);
  // North-east at 10 m/s, turning left at 0.2 rad/s, 10 Hz.
  for (int k = 0; k < 20; ++k) {
    const double t = 0.1 * k, yaw = 0.3 + 0.2 * t;
    PoseEstimate e;
    e.position[0] = 100 + 6 * t;
    e.position[1] = 50 + 8 * t;
    e.orientation[0] = std::cos(yaw / 2);
    e.orientation[3] = std::sin(yaw / 2);
    e.has_sigma = true;
    e.sigma_position_m[0] = e.sigma_position_m[1] = 1.0;
    e.sigma_rotation_rad[2] = 0.01;
    g.check(e, t, 0);
  }
  ASSERT_TRUE(g.motion(1.9, 1.95, &dx, &dy, &dyaw));
  EXPECT_NEAR(dx, 0.3, 1e-6);
  EXPECT_NEAR(dy, 0.4, 1e-6);
  EXPECT_NEAR(dyaw, 0.01, 1e-6);
}

}  // namespace
}  // namespace aprt
