// PointNet++ operators (issue #5): the references do what
// kernels/points/pointnet__ref.h says on hand-made points; the fast kernels
// equal them exactly (indices and values) on random clouds of odd sizes,
// with duplicate points (ties), strides wider than the coordinates, and radii
// from empty to whole-cloud neighbourhoods.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "kernels/points/pointnet__ref.h"
#include "kernels/points/pointnet_fast.h"
#include "kernels/preprocess/lidar_input.h"

namespace aprt::kernels {
namespace {

// n points of `stride` floats, coordinates in [-1, 1] (some quantised to a
// coarse grid so that distances tie), every 7th point a copy of an earlier one.
std::vector<float> random_rows(size_t n, size_t stride, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<float> x(n * stride);
  for (size_t i = 0; i < n; ++i) {
    for (size_t k = 0; k < stride; ++k) {
      float v = u(rng);
      if (k < 3 && i % 3 == 0) v = std::round(v * 4.0f) / 4.0f;
      x[i * stride + k] = v;
    }
    if (i >= 7 && i % 7 == 0) {
      const size_t j = rng() % i;
      for (size_t k = 0; k < 3; ++k) x[i * stride + k] = x[j * stride + k];
    }
  }
  return x;
}

TEST(PointNet, FpsByHand) {
  // On a line at 0, 4, 10, 6, 1: first 0, then the farthest (10); then 4 and 6
  // are both 4 from the chosen {0, 10}: the lower index (4) wins; then 6.
  const std::vector<float> p = {0, 0, 0, 4, 0, 0, 10, 0, 0, 6, 0, 0, 1, 0, 0};
  uint32_t idx[4];
  std::vector<float> dist(5);
  f32_fps__ref(p.data(), 3, 5, 4, idx, dist.data());
  EXPECT_EQ(idx[0], 0u);
  EXPECT_EQ(idx[1], 2u);
  EXPECT_EQ(idx[2], 1u);
  EXPECT_EQ(idx[3], 3u);
}

TEST(PointNet, FpsFastEqualsReference) {
  for (size_t n : {size_t(1), size_t(3), size_t(17), size_t(257), size_t(4099)}) {
    for (size_t stride : {size_t(3), size_t(6), size_t(7)}) {
      const auto p = random_rows(n, stride, uint32_t(n * 31 + stride));
      for (size_t count : {size_t(1), std::min(n, size_t(5)), (n + 1) / 2, n}) {
        std::vector<uint32_t> want(count), got(count);
        std::vector<float> dist(n), soa(3 * n), dist2(n);
        f32_fps__ref(p.data(), stride, n, count, want.data(), dist.data());
        f32_points_to_soa(p.data(), stride, n, soa.data());
        f32_fps_soa(soa.data(), n, count, got.data(), dist2.data());
        ASSERT_EQ(got, want) << "n " << n << " stride " << stride << " count " << count;
      }
    }
  }
}

TEST(PointNet, BallGroupByHand) {
  // Points (x only): 0, 0.5, 3, 0.2. Centre 0 radius 1: the first two inside in
  // index order are 0 and 0.5 (0.2 is third); k = 4 pads with the first.
  const std::vector<float> p = {0, 0, 0, 0.5f, 0, 0, 3, 0, 0, 0.2f, 0, 0};
  const std::vector<float> feats = {10, 11, 12, 13};
  const std::vector<float> centres = {0, 0, 0, 10, 0, 0};
  std::vector<float> y(2 * 4 * 4, -1.0f);
  f32_ball_group__ref(p.data(), 3, 4, centres.data(), 3, 0, 2, 1.0f, 4, feats.data(), 1, y.data());
  const float want0[4][4] = {{0, 0, 0, 10}, {0.5f, 0, 0, 11}, {0.2f, 0, 0, 13}, {0, 0, 0, 10}};
  for (int j = 0; j < 4; ++j) {
    for (int c = 0; c < 4; ++c) EXPECT_EQ(y[j * 4 + c], want0[j][c]) << j << "," << c;
  }
  // Centre at 10: nothing within 1 -> point 0, relative to the centre, everywhere.
  for (int j = 0; j < 4; ++j) {
    EXPECT_EQ(y[16 + j * 4 + 0], -10.0f);
    EXPECT_EQ(y[16 + j * 4 + 3], 10.0f);
  }
  // Strictly inside: a point exactly at the radius is not taken.
  const std::vector<float> edge = {1, 0, 0, 0, 0, 0};
  std::vector<float> y2(2 * 3);
  f32_ball_group__ref(edge.data(), 3, 2, centres.data(), 3, 0, 1, 1.0f, 2, nullptr, 0, y2.data());
  EXPECT_EQ(y2[0], 0.0f);  // point 1 (the centre itself), then repeated
  EXPECT_EQ(y2[3], 0.0f);
}

TEST(PointNet, BallGroupFastEqualsReference) {
  std::mt19937 rng(5);
  for (size_t n : {size_t(3), size_t(65), size_t(1031)}) {
    const size_t stride = 6;
    const auto p = random_rows(n, stride, uint32_t(n));
    const int s = int(std::min<size_t>(n, 37));
    for (int c_feat : {0, 1, 5, 17}) {
      std::vector<float> feats(n * size_t(c_feat));
      for (float& f : feats) f = float(rng() % 1000) / 100.0f;
      for (float radius : {0.01f, 0.3f, 5.0f}) {
        for (int k : {1, 7, 32}) {
          // Centres: points of the cloud (rows of width 6) and random ones.
          std::vector<float> centres(size_t(s) * 4);
          for (int i = 0; i < s; ++i) {
            for (int d = 0; d < 3; ++d) {
              centres[size_t(i) * 4 + d] =
                  i % 2 ? p[(size_t(i) * 13 % n) * stride + d] : float(rng() % 200) / 100.0f - 1;
            }
          }
          const size_t out = size_t(s) * size_t(k) * size_t(3 + c_feat);
          std::vector<float> want(out, -7.0f), got(out, -9.0f), soa(3 * n);
          const float* f = c_feat ? feats.data() : nullptr;
          f32_ball_group__ref(p.data(), stride, n, centres.data(), 4, 0, s, radius, k, f, c_feat,
                              want.data());
          f32_points_to_soa(p.data(), stride, n, soa.data());
          // In two parts, as the thread pool splits it.
          f32_ball_group_soa(soa.data(), n, centres.data(), 4, 0, s / 2, radius, k, f, c_feat,
                             got.data());
          f32_ball_group_soa(soa.data(), n, centres.data(), 4, s / 2, s, radius, k, f, c_feat,
                             got.data());
          ASSERT_EQ(got, want) << "n " << n << " c " << c_feat << " r " << radius << " k " << k;
        }
      }
    }
  }
}

TEST(PointNet, GroupMaxFastEqualsReference) {
  std::mt19937 rng(9);
  std::normal_distribution<float> g;
  for (int k : {1, 3, 32}) {
    for (int c : {1, 15, 64, 129}) {
      const int s = 11;
      std::vector<float> x(size_t(s) * k * c);
      for (float& v : x) v = g(rng);
      std::vector<float> want(size_t(s) * c), got(size_t(s) * c);
      f32_group_max__ref(k, c, x.data(), want.data(), 0, s);
      f32_group_max(k, c, x.data(), got.data(), 0, 4);
      f32_group_max(k, c, x.data(), got.data(), 4, s);
      ASSERT_EQ(got, want) << "k " << k << " c " << c;
      for (int f = 0; f < c; ++f) {  // and it is the maximum
        float m = -INFINITY;
        for (int j = 0; j < k; ++j) m = std::max(m, x[size_t(j) * c + f]);
        ASSERT_EQ(want[f], m);
      }
    }
  }
}

TEST(PointNet, ThreeInterpByHand) {
  // Known points at x = 0, 1, 2, 3 with features 0, 10, 20, 30; target x = 1:
  // nearest 1 (d2 0), then 0 and 2 tie at d2 1 (0 first), weights ~ (1e8, 1, 1).
  const std::vector<float> known = {0, 0, 0, 1, 0, 0, 2, 0, 0, 3, 0, 0};
  const std::vector<float> feats = {0, 10, 20, 30};
  const std::vector<float> target = {1, 0, 0, 1.5f, 0, 0};
  std::vector<float> y(2);
  f32_three_interp__ref(target.data(), 3, 0, 2, known.data(), 3, 4, feats.data(), 1, y.data());
  EXPECT_NEAR(y[0], 10.0f, 1e-5f);
  // x = 1.5: 1 and 2 (d2 0.25 each), then 0 and 3 tie at 2.25 -> 0 wins:
  // weights 4, 4, 1/2.25 over their sum.
  const float w = 4.0f + 4.0f + 1.0f / 2.25f;
  EXPECT_NEAR(y[1], (4.0f * 10 + 4.0f * 20 + 0.0f / 2.25f) / w, 1e-4f);
}

TEST(PointNet, ThreeInterpFastEqualsReference) {
  std::mt19937 rng(3);
  for (size_t nk : {size_t(3), size_t(4), size_t(63), size_t(257)}) {
    const auto known = random_rows(nk, 3, uint32_t(nk + 100));
    for (int c : {1, 7, 64, 130}) {
      const int nt = 45;
      const auto targets = random_rows(size_t(nt), 5, uint32_t(nk * 7 + size_t(c)));
      std::vector<float> feats(nk * size_t(c));
      for (float& f : feats) f = float(int(rng() % 2000) - 1000) / 97.0f;
      std::vector<float> want(size_t(nt) * c), got(size_t(nt) * c), soa(3 * nk), dist(nk);
      f32_three_interp__ref(targets.data(), 5, 0, nt, known.data(), 3, nk, feats.data(), c,
                            want.data());
      f32_points_to_soa(known.data(), 3, nk, soa.data());
      f32_three_interp_soa(targets.data(), 5, 0, 20, soa.data(), nk, feats.data(), c, got.data(),
                           dist.data());
      f32_three_interp_soa(targets.data(), 5, 20, nt, soa.data(), nk, feats.data(), c, got.data(),
                           dist.data());
      ASSERT_EQ(got, want) << "known " << nk << " c " << c;
    }
  }
}

TEST(PointNet, GridTokensByHand) {
  // 8 points, 2 groups x 2 slabs x 2 cells of one point each; feature = index.
  // z: the first four points are low. Within a group, x splits slabs, y cells.
  const std::vector<float> p = {1, 1, 0, 0, 0, 0, 0, 1, 0, 1, 0, 0,  // low: (1,1) (0,0) (0,1) (1,0)
                                1, 1, 5, 0, 0, 5, 0, 1, 5, 1, 0, 5};  // high, same layout
  std::vector<float> feats(8);
  for (int i = 0; i < 8; ++i) feats[i] = float(i);
  std::vector<float> y(8), scratch(4 * 8);
  f32_grid_tokens__ref(p.data(), 3, 8, 2, 2, 2, feats.data(), 1, y.data(), scratch.data());
  // group 0: slab x=0 -> (0,0)=1, (0,1)=2; slab x=1 -> (1,0)=3, (1,1)=0.
  const std::vector<float> want = {1, 2, 3, 0, 5, 6, 7, 4};
  EXPECT_EQ(y, want);
}

TEST(PointNet, GridTokensStableOnTies) {
  // Equal z everywhere: the groups follow index order; equal x within a
  // group: slabs keep the z-sorted (index) order; y then sorts each slab.
  const std::vector<float> p = {0, 3, 1, 0, 2, 1, 0, 1, 1, 0, 0, 1};
  const std::vector<float> feats = {30, 20, 10, 0};
  std::vector<float> y(4), scratch(16);
  f32_grid_tokens__ref(p.data(), 3, 4, 1, 2, 2, feats.data(), 1, y.data(), scratch.data());
  // slab 0 = points 0, 1 (y 3, 2) -> cells y=2 (20), y=3 (30); slab 1 = points 2, 3.
  const std::vector<float> want = {20, 30, 0, 10};
  EXPECT_EQ(y, want);
  // Max over a cell of two points.
  std::vector<float> y1(2);
  f32_grid_tokens__ref(p.data(), 3, 4, 1, 1, 2, feats.data(), 1, y1.data(), scratch.data());
  EXPECT_EQ(y1[0], 10.0f);  // y = 0, 1
  EXPECT_EQ(y1[1], 30.0f);  // y = 2, 3
}

TEST(PointNet, GridTokensSurviveNonFinite) {
  // Never reached through the point gate, but a total order keeps the sort
  // defined (and in bounds) whatever the coordinates are.
  std::vector<float> p = random_rows(64, 3, 4);
  p[5] = NAN;
  p[11] = INFINITY;
  p[20] = -INFINITY;
  std::vector<float> feats(64 * 3, 1.0f), y(16 * 3), scratch(4 * 64);
  f32_grid_tokens__ref(p.data(), 3, 64, 4, 2, 2, feats.data(), 3, y.data(), scratch.data());
  for (float v : y) EXPECT_EQ(v, 1.0f);
}

TEST(PointNet, PointsInputCropsSamplesAndNormalises) {
  PointsInputParams prm{4, 10.0f, 5.0f, {0, 0, 0, 0, 0, 0}, {1, 1, 1, 1, 1, 1}};
  // Five points inside 10 m, one outside (dropped by the crop).
  const std::vector<LidarPoint> pts = {{0, 0, 0, 0}, {5, 0, 0, 0},  {20, 0, 0, 0},
                                       {0, 5, 0, 0}, {0, -5, 1, 0}, {-5, 0, 0, 0}};
  std::vector<float> scratch(lidar_points_input_scratch(pts.size(), prm.samples));
  std::vector<float> out(4 * 6);
  for (bool fast : {false, true}) {
    const auto r =
        lidar_points_input(prm, pts.data(), pts.size(), fast, scratch.data(), out.data());
    EXPECT_EQ(r.points, 5u);
    EXPECT_TRUE(r.enough);
    // Sampled: 0 (origin), then the farthest points; features abs = p / 5.
    EXPECT_EQ(out[0], 0.0f);
    for (int i = 0; i < 4; ++i) {
      float mean_x = 0;
      for (int j = 0; j < 4; ++j) mean_x += out[j * 6];
      mean_x /= 4;
      EXPECT_NEAR(out[i * 6 + 3], out[i * 6] - mean_x, 1e-6f);  // rel = abs - mean
    }
  }
  // Too few points: padded by repetition, flagged.
  const auto r = lidar_points_input(prm, pts.data(), 2, true, scratch.data(), out.data());
  EXPECT_FALSE(r.enough);
  EXPECT_EQ(out[2 * 6], out[0]);
  // Empty (or everything cropped): zeros, flagged.
  const auto e = lidar_points_input(prm, pts.data() + 2, 1, true, scratch.data(), out.data());
  EXPECT_EQ(e.points, 0u);
  EXPECT_FALSE(e.enough);
  for (float v : out) EXPECT_EQ(v, 0.0f);
}

}  // namespace
}  // namespace aprt::kernels
