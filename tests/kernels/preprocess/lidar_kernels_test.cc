// LiDAR preprocessing (issue #5): the fast kernels equal their references
// exactly on random scans of odd sizes; the references do what
// runtime/base/lidar_point.h says, on hand-made points.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "kernels/preprocess/lidar__ref.h"
#include "kernels/preprocess/lidar_fast.h"

namespace aprt::kernels {
namespace {

std::vector<LidarPoint> random_scan(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> xy(-40.0f, 40.0f), z(-3.0f, 8.0f), in(0.0f, 1.0f);
  std::vector<LidarPoint> p(n);
  for (LidarPoint& q : p) q = {xy(rng), xy(rng), z(rng), in(rng)};
  return p;
}

TEST(Lidar, BevHistogramByHand) {
  const BevParams b{4, 1.0f, -2.0f, -2.0f, 0.5f, 2.0f};
  const std::vector<LidarPoint> p = {
      {-1.5f, -1.5f, 0.0f, 0},  // row 0, col 0, below
      {-1.5f, -1.5f, 0.2f, 0},  // same cell: count 2 = clip
      {-1.5f, -1.5f, 0.3f, 0},  // 3, clipped to 2
      {1.0f, 0.0f, 2.0f, 0},    // x = 1.0: row 3 (lower edge belongs to the cell), col 2, above
      {2.0f, 0.0f, 0.0f, 0},    // x = 2.0: outside (the grid ends before 2.0)
      {0.0f, -2.5f, 0.0f, 0},   // y outside
  };
  std::vector<float> out(4 * 4 * 2, -1.0f);
  lidar_bev_histogram__ref(p.data(), p.size(), b, out.data());
  EXPECT_EQ(out[(0 * 4 + 0) * 2 + 0], 1.0f);
  EXPECT_EQ(out[(0 * 4 + 0) * 2 + 1], 0.0f);
  EXPECT_EQ(out[(3 * 4 + 2) * 2 + 1], 0.5f);
  float sum = 0;
  for (float v : out) sum += v;
  EXPECT_EQ(sum, 1.5f);  // nothing else counted
}

TEST(Lidar, BevHistogramFastEqualsReference) {
  for (size_t n : {size_t(0), size_t(1), size_t(17), size_t(4097), size_t(120000)}) {
    const auto p = random_scan(n, uint32_t(n) + 1);
    for (const BevParams& b : {BevParams{256, 0.125f, -16.0f, -16.0f, 0.2f, 5.0f},
                               BevParams{33, 1.7f, -30.0f, -20.0f, 1.5f, 1.0f},
                               BevParams{64, 0.5f, 0.0f, -16.0f, -1.0f, 70000.0f}}) {
      const size_t cells = size_t(b.grid) * b.grid * 2;
      std::vector<float> want(cells), got(cells);
      std::vector<uint16_t> counts(cells);
      lidar_bev_histogram__ref(p.data(), n, b, want.data());
      lidar_bev_histogram(p.data(), n, b, counts.data(), got.data());
      ASSERT_EQ(got, want) << "n " << n << " grid " << b.grid;
    }
  }
}

TEST(Lidar, RadiusCropKeepsOrder) {
  std::vector<LidarPoint> p = {{1, 1, 0, 0}, {30, 0, 0, 0}, {0, -19.99f, 5, 0}, {20, 0.1f, 0, 0}};
  ASSERT_EQ(lidar_radius_crop__ref(p.data(), p.size(), 20.0f), 2u);
  EXPECT_EQ(p[0].x, 1.0f);
  EXPECT_EQ(p[1].y, -19.99f);
}

TEST(Lidar, FarthestPointSamplingByHand) {
  // On a line: 0 first, then the far end, then the middle.
  const std::vector<LidarPoint> p = {{0, 0, 0, 0}, {1, 0, 0, 0}, {10, 0, 0, 0}, {5, 0, 0, 0}};
  uint32_t idx[4];
  std::vector<float> dist(p.size());
  ASSERT_TRUE(lidar_fps__ref(p.data(), p.size(), 3, idx, dist.data()));
  EXPECT_EQ(idx[0], 0u);
  EXPECT_EQ(idx[1], 2u);
  EXPECT_EQ(idx[2], 3u);
  // Fewer points than samples: deterministic padding, flagged.
  uint32_t more[7];
  EXPECT_FALSE(lidar_fps__ref(p.data(), p.size(), 7, more, dist.data()));
  EXPECT_EQ(more[4], more[0]);
  EXPECT_EQ(more[6], more[2]);
  // No points at all: zeros, flagged.
  EXPECT_FALSE(lidar_fps__ref(p.data(), 0, 3, idx, dist.data()));
  EXPECT_EQ(idx[2], 0u);
}

TEST(Lidar, FarthestPointSamplingFastEqualsReference) {
  for (size_t n : {size_t(1), size_t(5), size_t(33), size_t(1000), size_t(20011)}) {
    auto p = random_scan(n, uint32_t(n) * 7 + 3);
    if (n > 10) p[n / 2] = p[n / 3];  // a duplicate point: ties must resolve alike
    for (size_t count : {size_t(1), size_t(16), size_t(1024)}) {
      std::vector<uint32_t> want(count), got(count);
      std::vector<float> dist(n), scratch(4 * n);
      const bool a = lidar_fps__ref(p.data(), n, count, want.data(), dist.data());
      const bool b = lidar_fps(p.data(), n, count, got.data(), scratch.data());
      EXPECT_EQ(a, b);
      ASSERT_EQ(got, want) << "n " << n << " count " << count;
    }
  }
}

}  // namespace
}  // namespace aprt::kernels
