#include "runtime/engine/pose_decode.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

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
  EXPECT_STREQ(pose_flags_text(kPoseNonFinite | kPoseOutOfBounds, text, sizeof text),
               "non-finite,out-of-bounds");
}

}  // namespace
}  // namespace aprt
