// int8 LINEAR and DWCONV2D in the engine (issue #4): loading, every kernel
// path against the int8 reference, determinism across threads, no allocation,
// and the loader's refusals of inconsistent quantisation parameters.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "runtime/base/allocation_counter.h"
#include "runtime/engine/engine.h"
#include "tests/support/model_builder.h"

namespace aprt {
namespace {

using test::ModelBuilder;

void fill_input(Engine& e) {
  for (size_t i = 0; i < e.input().numel; ++i) e.input().f32()[i] = std::sin(0.37f * float(i));
}

Expected<std::unique_ptr<Engine>> load(const std::vector<uint8_t>& b, const char* isa,
                                       int threads = 1) {
  EngineOptions o;
  o.isa = isa;
  o.threads = threads;
  return Engine::load_memory(b.data(), b.size(), o);
}

std::vector<float> run_once(Engine& e) {
  fill_input(e);
  EXPECT_TRUE(e.run());
  return std::vector<float>(e.output().f32(), e.output().f32() + 7);
}

TEST(Int8Linear, LoadsRunsAndAllocatesNothing) {
  const auto b = test::make_small_int8_model();
  auto loaded = load(b, nullptr);
  ASSERT_TRUE(loaded) << loaded.error().message();
  Engine& e = **loaded;
  const auto first = run_once(e);
  for (float v : first) EXPECT_TRUE(std::isfinite(v));
  const AllocationScope scope;
  for (int i = 0; i < 200; ++i) {
    fill_input(e);
    ASSERT_TRUE(e.run());
  }
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_EQ(std::memcmp(first.data(), e.output().f32(), 7 * sizeof(float)), 0);
}

TEST(Int8Linear, DiffersFromTheFp32ModelOnlyByQuantisation) {
  // Same graph, proj in fp32 with the dequantised weights: outputs close, not equal.
  auto fp32 = test::make_small_model([](ModelBuilder& b) {
    std::vector<float> w(16 * 8);
    for (size_t i = 0; i < w.size(); ++i) {
      const int j = int(i / 8);
      w[i] = float(int((i * 37 + 11) % 255) - 127) * (0.004f + 0.0005f * float(j));
    }
    b.set_data(b.tensor_index("proj.w"), w);
  });
  auto a = load(fp32, "ref");
  auto q = load(test::make_small_int8_model(), "ref");
  ASSERT_TRUE(a && q);
  const auto ya = run_once(**a), yq = run_once(**q);
  double worst = 0, scale = 0;
  for (int i = 0; i < 7; ++i) {
    worst = std::max(worst, double(std::fabs(ya[i] - yq[i])));
    scale = std::max(scale, double(std::fabs(ya[i])));
  }
  EXPECT_GT(worst, 0.0);
  EXPECT_LT(worst, 0.05 * scale);
}

TEST(Int8Linear, EveryIsaMatchesTheInt8Reference) {
  const auto b = test::make_small_int8_model();
  auto ref = load(b, "ref");
  ASSERT_TRUE(ref) << ref.error().message();
  const auto want = run_once(**ref);
  int checked = 0;
  for (const char* isa : {"avx512", "avx2", "neon"}) {
    auto e = load(b, isa);
    if (!e && e.error().code() == Errc::kIsaUnavailable) continue;  // not this CPU / build
    ASSERT_TRUE(e) << e.error().message();
    const auto got = run_once(**e);
    for (int i = 0; i < 7; ++i)
      EXPECT_NEAR(got[i], want[i], 1e-4f * (1 + std::fabs(want[i]))) << isa;
    ++checked;
  }
  EXPECT_GE(checked, 1);
}

TEST(Int8Linear, TwoThreadsGiveTheSameBits) {
  const auto b = test::make_small_int8_model();
  auto one = load(b, nullptr, 1), two = load(b, nullptr, 2);
  ASSERT_TRUE(one && two);
  const auto a = run_once(**one), c = run_once(**two);
  EXPECT_EQ(std::memcmp(a.data(), c.data(), sizeof(float) * 7), 0);
}

void expect_refused(void (*edit)(ModelBuilder&), const char* needle) {
  const auto b = test::make_small_int8_model(edit);
  auto e = Engine::load_memory(b.data(), b.size());
  ASSERT_FALSE(e) << "accepted; expected: " << needle;
  EXPECT_NE(std::string(e.error().message()).find(needle), std::string::npos)
      << e.error().message();
}

TEST(Int8Linear, LoaderRefusesInconsistentQuantisation) {
  expect_refused(
      [](ModelBuilder& b) {
        std::vector<float> s(16, 0.01f);
        s[3] = -0.5f;
        b.set_data(b.tensor_index("proj.w.qscale"), s);
      },
      "per-channel scale 3 of 'proj.w.int8' is -0.5");
  expect_refused(
      [](ModelBuilder& b) {
        std::vector<float> s(16, 0.01f);
        s[0] = 0.0f;
        b.set_data(b.tensor_index("proj.w.qscale"), s);
      },
      "per-channel scale 0 of 'proj.w.int8' is 0");
  expect_refused(
      [](ModelBuilder& b) {
        const int w = b.tensor_index("proj.w.int8");
        b.set_quant(w, 0.01f, 0, b.tensor_index("proj.w.qscale"));
      },
      "needs exactly one of a per-tensor scale or per-channel scales (has both)");
  expect_refused([](ModelBuilder& b) { b.set_quant(b.tensor_index("proj.w.int8"), 0, 0, -1); },
                 "(has neither)");
  expect_refused(
      [](ModelBuilder& b) { b.set_quant(b.tensor_index("proj.w.int8"), 0.01f, 200, -1); },
      "zero point 200 out of range [-128, 127]");
  expect_refused([](ModelBuilder& b) { b.set_quant(b.tensor_index("proj.w.int8"), 0.01f, 3, -1); },
                 "zero point 3 (symmetric weights need 0)");
  expect_refused([](ModelBuilder& b) { b.set_quant(b.tensor_index("proj.w.int8"), -1.0f, 0, -1); },
                 "quantisation scale -1");
  expect_refused(
      [](ModelBuilder& b) {
        b.set_quant(b.tensor_index("proj.w.int8"), 0, 0, b.tensor_index("proj.b"));
        b.set_dims(b.tensor_index("proj.b"), {8});
        b.set_data(b.tensor_index("proj.b"), std::vector<float>(8, 0.1f));
      },
      "have 8 per-channel scales for 16 output channels");
  expect_refused(
      [](ModelBuilder& b) { b.set_param(b.op_index("proj"), 1, ModelBuilder::f32_bits(0.0f)); },
      "input quantisation scale 0");
  expect_refused(
      [](ModelBuilder& b) {
        b.set_param(b.op_index("proj"), 1, ModelBuilder::f32_bits(std::nanf("")));
      },
      "input quantisation scale nan");
  expect_refused([](ModelBuilder& b) { b.set_param(b.op_index("proj"), 2, 256); },
                 "input zero point 256 out of range [0, 255]");
  expect_refused([](ModelBuilder& b) { b.set_param(b.op_index("proj"), 2, -1); },
                 "input zero point -1 out of range [0, 255]");
  expect_refused(
      [](ModelBuilder& b) {
        b.set_quant(b.tensor_index("proj.b"), 0, 0, b.tensor_index("proj.w.qscale"));
      },
      "tensor 'proj.b' of type f32 has per-channel quantisation scales");
}

// The small model's depthwise 3x3 ("dw", 8 channels, SiLU) in int8 as well.
void int8_dw(ModelBuilder& b) {
  const int op = b.op_index("dw");
  std::vector<float> scales(8);
  std::vector<int8_t> w(3 * 3 * 8);
  for (int c = 0; c < 8; ++c) scales[c] = 0.003f + 0.001f * float(c);
  for (size_t i = 0; i < w.size(); ++i) w[i] = int8_t(int((i * 53 + 7) % 255) - 127);
  const int qs = b.constant("dw.w.qscale", {8}, scales);
  const int wq = b.constant_i8("dw.w.int8", {3, 3, 8}, w, 0.0f, qs);
  b.set_inputs(op, {b.tensor_index("stem.out"), wq, b.tensor_index("dw.b")});
  b.set_param(op, 7, ModelBuilder::f32_bits(0.03f));
  b.set_param(op, 8, 17);
}

TEST(Int8DwConv, EveryIsaMatchesTheInt8ReferenceWithoutAllocating) {
  const auto b = test::make_small_int8_model(int8_dw);
  auto ref = load(b, "ref");
  ASSERT_TRUE(ref) << ref.error().message();
  const auto want = run_once(**ref);
  int checked = 0;
  for (const char* isa : {"avx512", "avx2", "neon"}) {
    auto e = load(b, isa, 2);
    if (!e && e.error().code() == Errc::kIsaUnavailable) continue;
    ASSERT_TRUE(e) << e.error().message();
    const auto got = run_once(**e);
    for (int i = 0; i < 7; ++i)
      EXPECT_NEAR(got[i], want[i], 1e-3f * (1 + std::fabs(want[i]))) << isa;
    const AllocationScope scope;
    for (int r = 0; r < 20; ++r) ASSERT_TRUE((*e)->run());
    EXPECT_EQ(scope.count(), 0u);
    ++checked;
  }
  EXPECT_GE(checked, 1);
}

TEST(Int8DwConv, LoaderRefusesBadParameters) {
  expect_refused(
      [](ModelBuilder& b) {
        int8_dw(b);
        b.set_param(b.op_index("dw"), 8, 300);
      },
      "input zero point 300 out of range [0, 255]");
  expect_refused(
      [](ModelBuilder& b) {
        int8_dw(b);
        b.set_param(b.op_index("dw"), 7, ModelBuilder::f32_bits(-0.1f));
      },
      "input quantisation scale -0.1");
  expect_refused(
      [](ModelBuilder& b) {
        int8_dw(b);
        b.set_quant(b.tensor_index("dw.w.int8"), 0, 0, b.tensor_index("proj.w.qscale"));
      },
      "must be an f32 constant of one value per channel (3, or 8 for depthwise weights)");
}

}  // namespace
}  // namespace aprt
