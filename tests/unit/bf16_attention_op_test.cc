// ATTENTION in bf16 (precision 2, issue #4) in the engine: the kernel each
// ISA picks, every path against the bf16 reference, determinism across
// threads, no allocation per frame.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "kernels/table/cpu_features.h"
#include "runtime/base/allocation_counter.h"
#include "runtime/engine/engine.h"
#include "tests/support/model_builder.h"

namespace aprt {
namespace {

using test::ModelBuilder;

std::vector<uint8_t> bf16_model() {
  return test::make_small_model([](ModelBuilder& m) { m.set_param(m.op_index("attn"), 2, 2); });
}

Expected<std::unique_ptr<Engine>> load(const std::vector<uint8_t>& b, const char* isa,
                                       int threads = 1) {
  EngineOptions o;
  o.isa = isa;
  o.threads = threads;
  return Engine::load_memory(b.data(), b.size(), o);
}

std::vector<float> run_once(Engine& e) {
  for (size_t i = 0; i < e.input().numel; ++i) e.input().f32()[i] = std::sin(0.37f * float(i));
  EXPECT_TRUE(e.run());
  return std::vector<float>(e.output().f32(), e.output().f32() + 7);
}

const OpNode& attention_node(const Engine& e) {
  for (size_t i = 0; i < e.op_count(); ++i) {
    if (e.op(i).code == format::OpCode::kAttention) return e.op(i);
  }
  ADD_FAILURE() << "no attention op";
  return e.op(0);
}

TEST(Bf16AttentionOp, PicksTheBf16KernelWhereTheCpuHasOne) {
  const auto b = bf16_model();
  auto e = load(b, "avx512");
  if (!e && e.error().code() == Errc::kIsaUnavailable) GTEST_SKIP() << "no AVX-512 here";
  ASSERT_TRUE(e) << e.error().message();
  const std::string kernel = attention_node(**e).kernel;
  EXPECT_EQ(kernel, kernels::cpu_features().avx512_bf16 ? "avx512bf16" : "avx512");
  auto avx2 = load(b, "avx2");
  ASSERT_TRUE(avx2) << avx2.error().message();
  EXPECT_STREQ(attention_node(**avx2).kernel, "avx2");  // Q, K, V rounded, fp32 kernel
}

// The paths agree to bf16's precision (the weights round against different
// references) and differ from the fp32 model's output (they did round).
TEST(Bf16AttentionOp, EveryIsaMatchesTheBf16Reference) {
  const auto b = bf16_model();
  auto ref = load(b, "ref");
  ASSERT_TRUE(ref) << ref.error().message();
  const auto want = run_once(**ref);
  const auto fp32_bytes = test::make_small_model();
  auto fp32 = load(fp32_bytes, "ref");
  ASSERT_TRUE(fp32);
  const auto plain = run_once(**fp32);
  EXPECT_NE(std::memcmp(want.data(), plain.data(), sizeof(float) * 7), 0);
  int checked = 0;
  for (const char* isa : {"avx512", "avx2", "neon"}) {
    auto e = load(b, isa);
    if (!e && e.error().code() == Errc::kIsaUnavailable) continue;  // not this CPU / build
    ASSERT_TRUE(e) << e.error().message();
    const auto got = run_once(**e);
    for (int i = 0; i < 7; ++i)
      EXPECT_NEAR(got[i], want[i], 1e-2f * (1 + std::fabs(want[i]))) << isa << " " << i;
    ++checked;
  }
  EXPECT_GE(checked, 1);
}

TEST(Bf16AttentionOp, RunsWithoutAllocatingAndTwoThreadsGiveTheSameBits) {
  const auto b = bf16_model();
  auto one = load(b, nullptr, 1), two = load(b, nullptr, 2);
  ASSERT_TRUE(one && two);
  const auto a = run_once(**one);
  const auto c = run_once(**two);
  EXPECT_EQ(std::memcmp(a.data(), c.data(), sizeof(float) * 7), 0);
  const AllocationScope scope;
  for (int i = 0; i < 200; ++i) ASSERT_TRUE((**one).run());
  EXPECT_EQ(scope.count(), 0u);
}

// Where the op prepares Q, K (, V) itself -- rounded to bf16, or int8 scores
// fake-quantised -- it does so in row tasks: two threads must give one
// thread's bits, on every ISA that takes that path here.
TEST(Bf16AttentionOp, PreparationInRowTasksGivesOneThreadsBits) {
  for (int precision : {1, 2}) {
    const auto b =
        precision == 1
            ? test::make_small_model([](ModelBuilder& m) { m.set_param(m.op_index("attn"), 2, 1); })
            : bf16_model();
    for (const char* isa : {"avx2", "neon"}) {
      auto one = load(b, isa, 1), two = load(b, isa, 2);
      if (!one && one.error().code() == Errc::kIsaUnavailable) continue;  // not this CPU / build
      ASSERT_TRUE(one && two) << isa;
      const auto a = run_once(**one);
      const auto c = run_once(**two);
      EXPECT_EQ(std::memcmp(a.data(), c.data(), sizeof(float) * 7), 0)
          << isa << " precision " << precision;
    }
  }
}

}  // namespace
}  // namespace aprt
