// The PointNet++ ops in the engine (issue #5): a small raw-points model loads,
// runs without allocating, gives the same pose on every ISA and thread count
// (the point ops pick identical indices on every path), and the loader
// refuses inconsistent point ops and metadata with messages that say which.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "runtime/base/allocation_counter.h"
#include "runtime/engine/engine.h"
#include "tests/support/model_builder.h"

namespace aprt {
namespace {

using test::ModelBuilder;

// Normalised-looking point features: x y z in [-1, 1], then the same minus their mean.
void fill_points(Engine& e) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  float* x = e.input().f32();
  const size_t n = e.input().numel / 6;
  double mean[3] = {};
  for (size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) mean[k] += (x[6 * i + k] = u(rng));
  }
  for (size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) x[6 * i + 3 + k] = x[6 * i + k] - float(mean[k] / double(n));
  }
}

std::vector<float> run_points(const char* isa, int threads) {
  const auto b = test::make_small_points_model();
  EngineOptions opt;
  opt.isa = isa;
  opt.threads = threads;
  opt.lock_memory = false;
  auto e = Engine::load_memory(b.data(), b.size(), opt);
  if (!e) return {};
  fill_points(**e);
  (void)(*e)->run();
  return std::vector<float>((*e)->output().f32(), (*e)->output().f32() + 7);
}

TEST(PointOps, SmallModelLoadsAndRunsWithoutAllocating) {
  const auto b = test::make_small_points_model();
  auto e = Engine::load_memory(b.data(), b.size());
  ASSERT_TRUE(e) << e.error().message();
  EXPECT_EQ((*e)->meta().modality, format::Modality::kLidarPoints);
  EXPECT_TRUE((*e)->meta().has_points);
  EXPECT_EQ((*e)->meta().points_crop_radius_m, 20.0f);
  fill_points(**e);
  ASSERT_TRUE((*e)->run());
  float first[7];
  std::memcpy(first, (*e)->output().f32(), sizeof first);
  for (float v : first) EXPECT_TRUE(std::isfinite(v));
  const AllocationScope scope;
  for (int i = 0; i < 200; ++i) {
    fill_points(**e);  // run() may reuse the input's memory once its last reader ran
    ASSERT_TRUE((*e)->run());
  }
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_EQ(std::memcmp(first, (*e)->output().f32(), sizeof first), 0);
}

TEST(PointOps, EveryIsaAndThreadCountAgree) {
  const auto ref = run_points("ref", 1);
  ASSERT_EQ(ref.size(), 7u);
  const auto one = run_points("auto", 1);
  ASSERT_EQ(one.size(), 7u);
  for (int threads : {2, 3}) {
    const auto many = run_points("auto", threads);
    EXPECT_EQ(std::memcmp(one.data(), many.data(), 7 * sizeof(float)), 0) << threads;
  }
  for (const char* isa : {"avx2", "avx512", "neon"}) {
    const auto got = run_points(isa, 2);
    if (got.empty()) continue;  // not compiled in / not runnable here
    for (int i = 0; i < 7; ++i) EXPECT_NEAR(got[i], ref[i], 1e-4 * (1 + std::fabs(ref[i]))) << isa;
  }
}

void expect_refused(void (*edit)(ModelBuilder&), const char* what) {
  const auto b = test::make_small_points_model(edit);
  auto e = Engine::load_memory(b.data(), b.size());
  ASSERT_FALSE(e) << "expected a refusal containing: " << what;
  EXPECT_NE(std::strstr(e.error().message(), what), nullptr) << e.error().message();
}

TEST(PointOps, LoaderRefusesInconsistentPointOps) {
  // More samples than points.
  expect_refused(
      [](ModelBuilder& m) {
        m.set_dims(m.tensor_index("fps2.out"), {1, 17, 1, 3});
        m.set_dims(m.tensor_index("group2.out"), {1, 17, 4, 11});
        m.set_dims(m.tensor_index("max2.out"), {1, 17, 1, 11});
      },
      "samples 17 of 16 points");
  // Coordinates need 3 columns.
  expect_refused(
      [](ModelBuilder& m) {
        m.set_dims(m.tensor_index("fps1.out"), {1, 16, 1, 2});
      },
      "rows of 3 coordinates");
  // A radius that is not a positive finite number.
  expect_refused(
      [](ModelBuilder& m) { m.set_param(m.op_index("group1"), 0, ModelBuilder::f32_bits(0.0f)); },
      "radius 0 must be finite and > 0");
  expect_refused(
      [](ModelBuilder& m) { m.set_param(m.op_index("group1"), 0, ModelBuilder::f32_bits(NAN)); },
      "must be finite");
  // Grouped output that does not fit the features.
  expect_refused(
      [](ModelBuilder& m) {
        m.set_dims(m.tensor_index("group1.out"), {1, 16, 4, 8});
      },
      "must be [1, 16, K, 9]");
  // Interpolation from fewer than three known points.
  expect_refused(
      [](ModelBuilder& m) {
        m.set_dims(m.tensor_index("fps2.out"), {1, 2, 1, 3});
        m.set_dims(m.tensor_index("group2.out"), {1, 2, 4, 11});
        m.set_dims(m.tensor_index("max2.out"), {1, 2, 1, 11});
      },
      "at least 3 known points");
  // Tokens that do not divide the points.
  expect_refused([](ModelBuilder& m) { m.set_param(m.op_index("tokens"), 0, 3); },
                 "16 points do not split into 3 x 2 x 2 cells");
  expect_refused([](ModelBuilder& m) { m.set_param(m.op_index("tokens"), 1, 0); },
                 "token grid 2 x 0 x 2");
  // GROUP_MAX output of the wrong shape.
  expect_refused(
      [](ModelBuilder& m) {
        m.set_dims(m.tensor_index("max1.out"), {1, 16, 2, 8});
      },
      "max1.out");
}

TEST(PointOps, LoaderRefusesInconsistentPointsMetadata) {
  expect_refused([](ModelBuilder& m) { m.points.clear(); }, "needs metadata 'points'");
  expect_refused([](ModelBuilder& m) { m.points = {0.0f, 20.0f}; }, "crop radius 0 m");
  expect_refused([](ModelBuilder& m) { m.points = {20.0f, -1.0f}; }, "coordinate scale -1 m");
  expect_refused([](ModelBuilder& m) { m.points = {20.0f}; }, "META key 51");
  // An image-shaped input under modality 3.
  const auto image = test::make_small_model([](ModelBuilder& m) {
    m.modality = 3;
    m.points = {20.0f, 20.0f};
  });
  auto e = Engine::load_memory(image.data(), image.size());
  ASSERT_FALSE(e);
  EXPECT_NE(std::strstr(e.error().message(), "N points x 1 x 6 features, not 8x8x3"), nullptr)
      << e.error().message();
}

}  // namespace
}  // namespace aprt
