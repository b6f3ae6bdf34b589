#include "runtime/engine/pose_decode.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "runtime/engine/ensemble_merge.h"
#include "runtime/pose/pose_flags.h"

namespace aprt {
namespace {

ModelMeta meta() {
  ModelMeta m;
  const float lo[3] = {-100, 50, 0}, hi[3] = {300, 250, 10};
  for (int i = 0; i < 3; ++i) m.pose_min[i] = lo[i], m.pose_max[i] = hi[i];
  return m;
}

TEST(PoseDecode, DenormalisesPositionAndNormalisesQuaternion) {
  const float raw[7] = {0.25f, 0.5f, 1.0f, 0.0f, 0.0f, 0.0f, 2.0f};
  const PoseEstimate p = decode_pose(raw, meta());
  EXPECT_TRUE(p.valid());
  EXPECT_NEAR(p.position[0], 0.0, 1e-9);
  EXPECT_NEAR(p.position[1], 150.0, 1e-9);
  EXPECT_NEAR(p.position[2], 10.0, 1e-9);
  EXPECT_NEAR(p.orientation[3], 1.0, 1e-12);
  EXPECT_NEAR(p.raw_quat_norm, 2.0f, 1e-6f);
}

TEST(PoseDecode, KeepsWNonNegative) {
  const float raw[7] = {0.5f, 0.5f, 0.5f, -0.5f, 0.5f, -0.5f, 0.5f};
  const PoseEstimate p = decode_pose(raw, meta());
  EXPECT_GE(p.orientation[0], 0.0);
  EXPECT_NEAR(p.orientation[0], 0.5, 1e-12);
  EXPECT_NEAR(p.orientation[1], -0.5, 1e-12);
}

TEST(PoseDecode, FlagsWhatCannotBeTrusted) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float bad[7] = {nan, 0.5f, 0.5f, 1, 0, 0, 0};
  EXPECT_TRUE(decode_pose(bad, meta()).flags & kPoseNonFinite);
  EXPECT_TRUE(decode_pose(bad, meta()).flags & kPoseOutOfBounds);
  const float zero_q[7] = {0.5f, 0.5f, 0.5f, 0, 0, 0, 0};
  const PoseEstimate z = decode_pose(zero_q, meta());
  EXPECT_TRUE(z.flags & kPoseQuatDegenerate);
  EXPECT_EQ(z.orientation[0], 1.0);
  const float far[7] = {1.5f, 0.5f, 0.5f, 1, 0, 0, 0};
  EXPECT_TRUE(decode_pose(far, meta()).flags & kPoseOutOfBounds);
  const float edge[7] = {1.05f, -0.05f, 0.5f, 1, 0, 0, 0};
  EXPECT_TRUE(decode_pose(edge, meta()).valid());  // within the 10 % margin
  const float small_q[7] = {0.5f, 0.5f, 0.5f, 0.1f, 0, 0, 0};
  EXPECT_TRUE(decode_pose(small_q, meta()).flags & kPoseQuatNorm);
  char text[64];
  EXPECT_STREQ(pose_flag_names(kPoseNonFinite | kPoseOutOfBounds, text, sizeof text),
               "non-finite,out-of-bounds");
  EXPECT_STREQ(pose_flag_names(0, text, sizeof text), "ok");
  EXPECT_STREQ(pose_flag_names(kPoseUnconfirmed | kPoseStaleFrame, text, sizeof text),
               "unconfirmed,stale");
  char tiny[8];  // truncated, never overrun
  EXPECT_STREQ(pose_flag_names(kPoseNonFinite | kPoseJump, tiny, sizeof tiny), "non-fin");
}

// Outputs 7..12 of a model with confidence (FORMAT.md 1.3): sigma = scale *
// sqrt(2) * exp(s), times the axis's extent for the position; non-finite
// confidence outputs flag the pose.
TEST(PoseDecode, ConfidenceOutputsBecomeStandardDeviations) {
  ModelMeta m = meta();
  m.has_uncertainty = true;
  m.uncertainty_scale[0] = 2.0f;
  m.uncertainty_scale[1] = 0.5f;
  const float raw[13] = {
      0.5f, 0.5f,          0.5f, 1, 0, 0, 0, std::log(0.01f), 0.0f, -30.0f, std::log(0.02f),
      0.0f, std::log(0.1f)};
  const PoseEstimate p = decode_pose(raw, m);
  ASSERT_TRUE(p.has_sigma);
  EXPECT_TRUE(p.valid());
  EXPECT_NEAR(p.sigma_position_m[0], 2.0 * std::sqrt(2.0) * 0.01 * 400.0, 1e-4);
  EXPECT_NEAR(p.sigma_position_m[1], 2.0 * std::sqrt(2.0) * 1.0 * 200.0, 1e-4);
  EXPECT_NEAR(p.sigma_position_m[2], 2.0 * std::sqrt(2.0) * std::exp(-14.0) * 10.0,
              1e-9);  // clamped
  EXPECT_NEAR(p.sigma_rotation_rad[0], 0.5 * std::sqrt(2.0) * 0.02, 1e-6);
  EXPECT_NEAR(p.sigma_rotation_rad[2], 0.5 * std::sqrt(2.0) * 0.1, 1e-6);
  float bad[13];
  std::copy(raw, raw + 13, bad);
  bad[11] = std::numeric_limits<float>::quiet_NaN();
  const PoseEstimate q = decode_pose(bad, m);
  EXPECT_FALSE(q.has_sigma);
  EXPECT_TRUE(q.flags & kPoseNoConfidence);
  // Without the calibration (a 7-output model) nothing past raw[6] is read.
  EXPECT_FALSE(decode_pose(raw, meta()).has_sigma);
}

// An ensemble's members side by side (FORMAT.md 1.5): merged, and their
// spread joins the network's own sigma before the calibration scale. The
// numbers of tests/tools/test_ensemble.py's merge test.
TEST(PoseDecode, AnEnsemblesMembersAreMergedAndTheirSpreadJoinsTheSigma) {
  ModelMeta m = meta();
  m.has_uncertainty = true;
  m.uncertainty_scale[0] = 2.0f;
  m.uncertainty_scale[1] = 0.5f;
  m.ensemble_members = 2;
  m.member_outputs = 2;
  const float s = std::log(0.01f);
  const float c = float(std::cos(0.1)), z = float(std::sin(0.1));
  const float raw[26] = {0.45f, 0.5f, 0.49f, 1,      0, 0, 0,      s, s, s, s, s, s,
                         0.55f, 0.5f, 0.51f, -2 * c, 0, 0, -2 * z, s, s, s, s, s, s};
  const PoseEstimate p = decode_pose(raw, m);
  ASSERT_TRUE(p.has_sigma);
  EXPECT_TRUE(p.valid());
  EXPECT_NEAR(p.position[0], -100 + 0.5 * 400, 1e-4);
  EXPECT_NEAR(p.position[2], 5.0, 1e-5);
  // The quaternion turned to one sign, then w >= 0: about z by 0.1 / 3 rad.
  const MergedOutputs merged = merge_members(raw, 2);
  EXPECT_NEAR(p.orientation[0], std::cos(std::atan2(z, (1 + 2 * c) / 2)), 1e-6);
  const double own = std::sqrt(2.0) * 0.01;
  EXPECT_NEAR(p.sigma_position_m[0], 2.0 * std::hypot(own, 0.05) * 400.0, 1e-3);
  EXPECT_NEAR(p.sigma_position_m[1], 2.0 * own * 200.0, 1e-4);
  EXPECT_NEAR(p.sigma_position_m[2], 2.0 * std::hypot(own, 0.01) * 10.0, 1e-4);
  EXPECT_NEAR(p.sigma_rotation_rad[0], 0.5 * own, 1e-6);
  EXPECT_NEAR(p.sigma_rotation_rad[2], 0.5 * std::hypot(own, merged.rotation_sd[2]), 1e-6);
  // A member's value not finite: flagged, no confidence.
  float bad[26];
  std::copy(raw, raw + 26, bad);
  bad[13] = std::numeric_limits<float>::infinity();
  const PoseEstimate q = decode_pose(bad, m);
  EXPECT_FALSE(q.valid());
  EXPECT_TRUE(q.flags & kPoseNonFinite);
}

}  // namespace
}  // namespace aprt
