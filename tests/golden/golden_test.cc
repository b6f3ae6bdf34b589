// Golden tests: the engine against PyTorch (or upstream's ONNX Runtime run).
//
// APRT_GOLDEN_DIR names a folder written by `python3 -m aprt_tools golden
// --convert`: model.aprt, in_K.f32 (NCHW, normalised) and out_K.f32 (7 values).
// The error measure: for each output i, |got_i - want_i| / max(|want_i|, 0.1 * max_j |want_j|),
// i.e. relative, with a floor at a tenth of the largest output so that values
// near zero are judged on the output's scale. The bound is 1e-4.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>

#include "runtime/common/allocation_counter.h"
#include "runtime/engine/engine.h"
#include "tests/support/test_files.h"

namespace aprt {
namespace {

constexpr double kTolerance = 1e-4;

double golden_error(const float* got, const std::vector<float>& want) {
  double scale = 0.0;
  for (float w : want) scale = std::max(scale, double(std::fabs(w)));
  double worst = 0.0;
  for (size_t i = 0; i < want.size(); ++i) {
    const double denom = std::max(double(std::fabs(want[i])), 0.1 * scale);
    worst = std::max(worst, std::fabs(double(got[i]) - want[i]) / denom);
  }
  return worst;
}

TEST(Golden, MatchesReference) {
  const std::string dir = test::env_dir("APRT_GOLDEN_DIR");
  if (dir.empty()) GTEST_SKIP() << "APRT_GOLDEN_DIR not set";
  auto loaded = Engine::load_file((dir + "/model.aprt").c_str());
  ASSERT_TRUE(loaded) << loaded.error().message();
  Engine& e = *loaded.value();
  const auto& shape = e.meta().input_shape;
  int checked = 0;
  for (int k = 0; std::filesystem::exists(dir + "/in_" + std::to_string(k) + ".f32"); ++k) {
    const auto x = test::read_f32(dir + "/in_" + std::to_string(k) + ".f32");
    const auto want = test::read_f32(dir + "/out_" + std::to_string(k) + ".f32");
    ASSERT_EQ(x.size(), e.input().numel);
    ASSERT_EQ(want.size(), 7u);
    const auto nhwc = test::nchw_to_nhwc(x, int(shape[3]), int(shape[1]), int(shape[2]));
    std::memcpy(e.input().f32(), nhwc.data(), nhwc.size() * sizeof(float));
    ASSERT_TRUE(e.run());
    const double err = golden_error(e.output().f32(), want);
    EXPECT_LE(err, kTolerance) << "input " << k;
    std::printf("golden %s input %d: max relative error %.2e\n", dir.c_str(), k, err);
    ++checked;
  }
  EXPECT_GE(checked, 1);
}

TEST(Golden, RunAllocatesNothing) {
  const std::string dir = test::env_dir("APRT_GOLDEN_DIR");
  if (dir.empty()) GTEST_SKIP() << "APRT_GOLDEN_DIR not set";
  auto loaded = Engine::load_file((dir + "/model.aprt").c_str());
  ASSERT_TRUE(loaded) << loaded.error().message();
  Engine& e = *loaded.value();
  (void)e.run();
  const AllocationScope scope;
  for (int i = 0; i < 20; ++i) ASSERT_TRUE(e.run());
  EXPECT_EQ(scope.count(), 0u);
}

}  // namespace
}  // namespace aprt
