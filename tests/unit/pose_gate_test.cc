// The validity gate (runtime/pose/pose_gate.h) on made-up drives: a track is
// confirmed by consistent estimates, an outlier is withheld and does not move
// it, a run of wrong estimates does not take over a live track, a lost track
// is replaced by a new confirmed one, an unconfident estimate is withheld.
#include "runtime/pose/pose_gate.h"

#include <gtest/gtest.h>

#include <cmath>

#include "runtime/base/allocation_counter.h"

namespace aprt {
namespace {

constexpr double kDt = 0.04;  // 25 Hz

// An estimate on a straight road heading east at 10 m/s, at frame k.
PoseEstimate on_road(int k, double dx = 0, double dy = 0, double yaw_deg = 0) {
  PoseEstimate p;
  p.position[0] = 10.0 + 10.0 * k * kDt + dx;
  p.position[1] = 50.0 + dy;
  p.position[2] = 1.55;
  const double yaw = yaw_deg * M_PI / 180.0;
  p.orientation[0] = std::cos(yaw / 2);
  p.orientation[3] = std::sin(yaw / 2);
  return p;
}

PoseGateParams params() {
  PoseGateParams p;
  p.confirm = 5;
  p.lost_after = 25;
  return p;
}

TEST(PoseGate, ConsistentEstimatesAreConfirmedThenValid) {
  PoseGate g(params());
  for (int k = 0; k < 4; ++k) EXPECT_EQ(g.check(on_road(k), k * kDt, 0), kPoseUnconfirmed) << k;
  EXPECT_EQ(g.check(on_road(4), 4 * kDt, 0), 0u);  // the fifth confirms the track
  for (int k = 5; k < 100; ++k) {
    const double noise = 1.5 * std::sin(k * 1.7);  // metres of estimation noise
    EXPECT_EQ(g.check(on_road(k, noise, -noise), k * kDt, 0), 0u) << k;
  }
  EXPECT_TRUE(g.tracking());
}

TEST(PoseGate, AnOutlierIsWithheldAndDoesNotMoveTheTrack) {
  PoseGate g(params());
  for (int k = 0; k < 30; ++k) g.check(on_road(k), k * kDt, 0);
  EXPECT_EQ(g.check(on_road(30, 0, 50), 30 * kDt, 0), kPoseInconsistent | kPoseJump);
  EXPECT_EQ(g.check(on_road(31, 0, 15), 31 * kDt, 0), kPoseInconsistent);     // 15 m: no jump
  EXPECT_EQ(g.check(on_road(32, 0, 0, 40), 32 * kDt, 0), kPoseInconsistent);  // wrong yaw
  EXPECT_EQ(g.check(on_road(33), 33 * kDt, 0), 0u);
}

TEST(PoseGate, AWrongRunDoesNotTakeOverALiveTrack) {
  PoseGate g(params());
  for (int k = 0; k < 30; ++k) g.check(on_road(k), k * kDt, 0);
  // 18 consistent estimates on the parallel street 50 m north (the town's
  // typical confusion), then the right street again.
  for (int k = 30; k < 48; ++k) {
    EXPECT_NE(g.check(on_road(k, 0, 50), k * kDt, 0) & kPoseInconsistent, 0u) << k;
  }
  EXPECT_EQ(g.check(on_road(48), 48 * kDt, 0), 0u);
}

TEST(PoseGate, ALostTrackIsReplacedByANewConfirmedOne) {
  PoseGate g(params());
  for (int k = 0; k < 30; ++k) g.check(on_road(k), k * kDt, 0);
  // The vehicle really is elsewhere (a relocalisation): 25 refusals end the
  // old track; the candidate, consistent all along, takes over.
  int k = 30;
  uint32_t f = 0;
  for (; k < 60; ++k) {
    f = g.check(on_road(k, 0, 80), k * kDt, 0);
    if (f == 0) break;
  }
  EXPECT_EQ(f, 0u);
  EXPECT_LE(k, 30 + params().lost_after);
  EXPECT_EQ(g.check(on_road(k + 1, 0, 80), (k + 1) * kDt, 0), 0u);
}

TEST(PoseGate, AnUnconfidentEstimateIsWithheld) {
  PoseGate g(params());
  for (int k = 0; k < 10; ++k) g.check(on_road(k), k * kDt, 0);
  PoseEstimate p = on_road(10);
  p.has_sigma = true;
  p.sigma_position_m[0] = p.sigma_position_m[1] = 1.0;  // 95 % radius 2.4 m
  p.sigma_rotation_rad[2] = 0.01;
  EXPECT_EQ(g.check(p, 10 * kDt, 0), 0u);
  p = on_road(11);
  p.has_sigma = true;
  p.sigma_position_m[0] = 5.0;  // 95 % radius 12.2 m > 8 m
  p.sigma_rotation_rad[2] = 0.01;
  EXPECT_EQ(g.check(p, 11 * kDt, 0) & kPoseUncertain, kPoseUncertain);
  p.sigma_position_m[0] = 1.0;
  p.sigma_rotation_rad[2] = 0.2;  // 95 % yaw 22 deg > 10 deg
  EXPECT_EQ(g.check(p, 11 * kDt, 0) & kPoseUncertain, kPoseUncertain);
}

TEST(PoseGate, YawTrackAcrossTheWrap) {
  PoseGate g(params());
  // Heading west (yaw +-180 deg) with yaw noise across the wrap.
  for (int k = 0; k < 40; ++k) {
    PoseEstimate p = on_road(0, -10.0 * k * kDt, 0, (k % 2) ? 179.0 : -179.0);
    const uint32_t f = g.check(p, k * kDt, 0);
    if (k >= 5) {
      EXPECT_EQ(f, 0u) << k;
    }
  }
}

TEST(PoseGate, FlaggedEstimatesAreNotUsedAndDisabledGateOnlyChecksJumps) {
  PoseGate g(params());
  for (int k = 0; k < 10; ++k) g.check(on_road(k), k * kDt, 0);
  EXPECT_NE(g.check(on_road(10), 10 * kDt, kPoseOutOfBounds), 0u);
  PoseGateParams off = params();
  off.enabled = false;
  PoseGate d(off);
  EXPECT_EQ(d.check(on_road(0), 0, 0), 0u);
  EXPECT_EQ(d.check(on_road(1, 0, 100), kDt, 0), kPoseJump);
}

TEST(GateClock, FramesOwnStampsOverArrival) {
  // A recording replayed as fast as the machine goes: frames arrive 1 ms
  // apart but were stamped 40 ms apart; the gate sees the 40 ms.
  GateClock c;
  const int64_t wall = 1796395395'551520857;  // a wall-clock stamp, ns
  EXPECT_EQ(c.seconds(5'000'000, wall), 0.0);
  EXPECT_DOUBLE_EQ(c.seconds(6'000'000, wall + 40'000'000), 0.040);
  EXPECT_DOUBLE_EQ(c.seconds(7'000'000, wall + 80'000'000), 0.080);
  // A frame without a stamp stays on the stamps' clock (last offset).
  EXPECT_DOUBLE_EQ(c.seconds(8'000'000, 0), 0.081);
  // Exact to the nanosecond however large the stamps are.
  EXPECT_EQ(c.seconds(9'000'000, wall + 1), 1e-9);
}

TEST(GateClock, ArrivalWhenNoFrameHasAStamp) {
  GateClock c;
  EXPECT_EQ(c.seconds(2'000'000'000, 0), 0.0);
  EXPECT_DOUBLE_EQ(c.seconds(2'100'000'000, 0), 0.1);
}

TEST(GateClock, StampsBeginningLateContinueTheClock) {
  // Two frames without a stamp, then stamps on another clock: no jump.
  GateClock c;
  const int64_t wall = 1796395395'000000000;
  EXPECT_EQ(c.seconds(1'000'000'000, 0), 0.0);
  EXPECT_DOUBLE_EQ(c.seconds(1'040'000'000, 0), 0.040);
  EXPECT_DOUBLE_EQ(c.seconds(1'080'000'000, wall), 0.080);
  EXPECT_DOUBLE_EQ(c.seconds(1'100'000'000, wall + 40'000'000), 0.120);
}

TEST(PoseGate, AllocatesNothing) {
  PoseGate g(params());
  const AllocationScope scope;
  for (int k = 0; k < 200; ++k) g.check(on_road(k, 0, (k / 40) % 2 ? 60 : 0), k * kDt, 0);
  EXPECT_EQ(scope.count(), 0u);
}

}  // namespace
}  // namespace aprt
