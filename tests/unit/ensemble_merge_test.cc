// An ensemble's members merged (runtime/engine/ensemble_merge.h): the numbers
// of tests/tools/test_ensemble.py's merge test, so the runtime and the
// calibration (tools/aprt_tools/ensemble_merge.py) are held to one result.
#include "runtime/engine/ensemble_merge.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace aprt {
namespace {

const float kS = std::log(0.01f);

TEST(EnsembleMerge, TurnsQuaternionsToOneSignAndMeasuresTheSpread) {
  const float c = float(std::cos(0.1)), z = float(std::sin(0.1));
  // Member b: the rotation 0.2 rad about z from a's, written as -q and longer.
  const float raw[26] = {0.45f, 0.5f, 0.49f, 1,      0, 0, 0,      kS, kS, kS, kS, kS, kS,
                         0.55f, 0.5f, 0.51f, -2 * c, 0, 0, -2 * z, kS, kS, kS, kS, kS, kS};
  const MergedOutputs m = merge_members(raw, 2);
  EXPECT_NEAR(m.raw[0], 0.5, 1e-6);
  EXPECT_NEAR(m.raw[2], 0.5, 1e-6);
  // b is the reference (the larger norm); a is turned to its sign.
  EXPECT_NEAR(m.raw[3], -(1 + 2 * c) / 2, 1e-6);
  EXPECT_NEAR(m.raw[6], -z, 1e-6);
  EXPECT_NEAR(m.raw[7], kS, 1e-6);
  EXPECT_NEAR(m.position_sd[0], 0.05, 1e-6);
  EXPECT_NEAR(m.position_sd[1], 0.0, 1e-9);
  EXPECT_NEAR(m.position_sd[2], 0.01, 1e-6);
  EXPECT_NEAR(m.rotation_sd[0], 0.0, 1e-9);
  EXPECT_GT(m.rotation_sd[2], 0.09);
  EXPECT_LT(m.rotation_sd[2], 0.11);
}

// With the signs agreeing, the merge is the plain mean; the order of the
// members does not matter.
TEST(EnsembleMerge, MembersOfOneSignAreAveragedInAnyOrder) {
  float raw[3 * 13];
  for (int i = 0; i < 3 * 13; ++i) raw[i] = 0.1f + 0.01f * float((i * 7) % 13) + 0.03f * (i / 13);
  const MergedOutputs m = merge_members(raw, 3);
  float swapped[3 * 13];
  for (int i = 0; i < 13; ++i) {
    swapped[i] = raw[26 + i];
    swapped[13 + i] = raw[i];
    swapped[26 + i] = raw[13 + i];
  }
  const MergedOutputs w = merge_members(swapped, 3);
  for (int k = 0; k < 13; ++k) {
    EXPECT_NEAR(m.raw[k], (raw[k] + raw[13 + k] + raw[26 + k]) / 3.0, 1e-6) << k;
    EXPECT_FLOAT_EQ(m.raw[k], w.raw[k]) << k;
  }
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(m.position_sd[a], w.position_sd[a], 1e-12);
}

// A member without a rotation (a zero quaternion) or with a NaN: the merge
// says so (non-finite spread or values), never a confident pose.
TEST(EnsembleMerge, ABrokenMemberIsNotHidden) {
  float raw[26] = {0.5f, 0.5f, 0.5f, 1, 0, 0, 0, kS, kS, kS, kS, kS, kS,
                   0.5f, 0.5f, 0.5f, 0, 0, 0, 0, kS, kS, kS, kS, kS, kS};
  MergedOutputs m = merge_members(raw, 2);
  EXPECT_FALSE(std::isfinite(m.rotation_sd[2]));
  raw[14] = std::numeric_limits<float>::quiet_NaN();
  m = merge_members(raw, 2);
  EXPECT_FALSE(std::isfinite(m.raw[1]));
}

}  // namespace
}  // namespace aprt
