// Golden tests: the engine against PyTorch (or upstream's ONNX Runtime run).
//
// APRT_GOLDEN_DIR names a folder written by `python3 -m aprt_tools golden
// --convert` (or golden-ensemble): model.aprt, in_K.f32 (NCHW, normalised) and
// out_K.f32 (the model's 7 values, 13 with the confidence outputs).
// The error measure: for each output i, |got_i - want_i| / max(|want_i|, 0.1 * max_j |want_j|),
// i.e. relative, with a floor at a tenth of the largest output so that values
// near zero are judged on the output's scale. The bound is 1e-4, or
// APRT_GOLDEN_TOLERANCE: int8 models are judged against the converter's
// statement of the int8 arithmetic, and an activation that an ISA's fp32 op
// computes a last bit differently can round to the neighbouring int8 step, a
// jump no fp32 tolerance describes (tests/CMakeLists.txt sets the bound).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include "runtime/base/allocation_counter.h"
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

// Loads the golden model with the kernels APRT_ISA names and APRT_THREADS
// threads; skips when this CPU cannot run that ISA.
Expected<std::unique_ptr<Engine>> load_golden(const std::string& dir) {
  EngineOptions opt;
  if (const char* t = std::getenv("APRT_THREADS")) opt.threads = std::atoi(t);
  return Engine::load_file((dir + "/model.aprt").c_str(), opt);
}

// Only "this CPU lacks the ISA" skips: every other refusal (batch size,
// integer activations, no kernel for an op's configuration) is the model
// failing its golden test.
bool isa_unsupported(const Error& e) {
  return e.code() == Errc::kIsaUnavailable;
}

TEST(Golden, MatchesReference) {
  const std::string dir = test::env_dir("APRT_GOLDEN_DIR");
  if (dir.empty()) GTEST_SKIP() << "APRT_GOLDEN_DIR not set";
  auto loaded = load_golden(dir);
  if (!loaded && isa_unsupported(loaded.error())) GTEST_SKIP() << loaded.error().message();
  ASSERT_TRUE(loaded) << loaded.error().message();
  Engine& e = *loaded.value();
  const auto& shape = e.meta().input_shape;
  const char* tol_env = std::getenv("APRT_GOLDEN_TOLERANCE");
  const double tolerance = tol_env ? std::atof(tol_env) : kTolerance;
  int checked = 0;
  for (int k = 0; std::filesystem::exists(dir + "/in_" + std::to_string(k) + ".f32"); ++k) {
    const auto x = test::read_f32(dir + "/in_" + std::to_string(k) + ".f32");
    const auto want = test::read_f32(dir + "/out_" + std::to_string(k) + ".f32");
    ASSERT_EQ(x.size(), e.input().numel);
    ASSERT_EQ(want.size(), e.output().numel);
    const auto nhwc = test::nchw_to_nhwc(x, int(shape[3]), int(shape[1]), int(shape[2]));
    std::memcpy(e.input().f32(), nhwc.data(), nhwc.size() * sizeof(float));
    ASSERT_TRUE(e.run());
    const double err = golden_error(e.output().f32(), want);
    EXPECT_LE(err, tolerance) << "input " << k;
    std::printf("golden %s input %d (%s kernels, %d threads): max relative error %.2e\n",
                dir.c_str(), k, e.isa(), e.threads(), err);
    ++checked;
  }
  EXPECT_GE(checked, 1);
}

TEST(Golden, RunAllocatesNothing) {
  const std::string dir = test::env_dir("APRT_GOLDEN_DIR");
  if (dir.empty()) GTEST_SKIP() << "APRT_GOLDEN_DIR not set";
  auto loaded = load_golden(dir);
  if (!loaded && isa_unsupported(loaded.error())) GTEST_SKIP() << loaded.error().message();
  ASSERT_TRUE(loaded) << loaded.error().message();
  Engine& e = *loaded.value();
  (void)e.run();
  const AllocationScope scope;
  for (int i = 0; i < 20; ++i) ASSERT_TRUE(e.run());
  EXPECT_EQ(scope.count(), 0u);
}

}  // namespace
}  // namespace aprt
