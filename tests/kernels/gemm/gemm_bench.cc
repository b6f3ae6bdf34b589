// The GEMM family on the model's shapes: fp32 (warm and as a chain of cold
// products) and int8.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "kernels/gemm/f32_gemm.h"
#include "kernels/gemm/qs8_gemm.h"
#include "kernels/table/kernel_table.h"
#include "tests/kernels/bench_support.h"

namespace aprt::kernels::bench {

// LINEAR: M x N x K with packed weights, one thread.
void BM_Gemm(benchmark::State& state) {
  const int m = int(state.range(0)), n = int(state.range(1)), k = int(state.range(2));
  const auto a = rnd(size_t(m) * k), w = rnd(size_t(n) * k), bias = rnd(n);
  Buf packed(f32_pack_b_floats(n, k, g_ks->gemm_nr)), c(size_t(m) * n);
  f32_pack_b(n, k, g_ks->gemm_nr, w.data(), packed.data());
  const GemmArgs g{m,
                   n,
                   k,
                   a.data(),
                   size_t(k),
                   packed.data(),
                   size_t(g_ks->gemm_nr),
                   size_t(k) * g_ks->gemm_nr,
                   true,
                   bias.data(),
                   nullptr,
                   0,
                   c.data(),
                   size_t(n),
                   Act::kNone};
  const int panels = (n + g_ks->gemm_nr - 1) / g_ks->gemm_nr;
  for (auto _ : state) {
    g_ks->gemm(g, 0, m, 0, panels);
    benchmark::DoNotOptimize(c.data());
  }
  add_peak_counter(state, 2.0 * m * n * k);
}

// LINEAR as the network runs it: a chain of `count` products of M x N x K,
// each with its own packed weights (cold: the chain's weights exceed L2) and
// the output of one the input of the next (ping-pong activations, like the
// arena) -- the in-network speed BM_Gemm's warm one is compared with.
void BM_GemmChain(benchmark::State& state) {
  const int m = int(state.range(0)), n = int(state.range(1)), k = int(state.range(2));
  const int count = int(state.range(3));
  if (n != k) {
    state.SkipWithError("a chain needs N == K");
    return;
  }
  auto w = rnd(size_t(n) * k);
  for (float& v : w) v *= 1.0f / 16;  // activations stay O(1) (the bias), never inf or denormal
  const auto bias = rnd(n);
  const size_t pf = f32_pack_b_floats(n, k, g_ks->gemm_nr);
  Buf packed(pf * size_t(count)), x0 = rnd(size_t(m) * k), x1(size_t(m) * n);
  for (int i = 0; i < count; ++i) f32_pack_b(n, k, g_ks->gemm_nr, w.data(), packed.data() + pf * i);
  const int panels = (n + g_ks->gemm_nr - 1) / g_ks->gemm_nr;
  for (auto _ : state) {
    for (int i = 0; i < count; ++i) {
      const float* in = (i % 2 == 0 ? x0 : x1).data();
      float* out = (i % 2 == 0 ? x1 : x0).data();
      const GemmArgs g{m,
                       n,
                       k,
                       in,
                       size_t(k),
                       packed.data() + pf * i,
                       size_t(g_ks->gemm_nr),
                       size_t(k) * g_ks->gemm_nr,
                       true,
                       bias.data(),
                       nullptr,
                       0,
                       out,
                       size_t(n),
                       Act::kNone};
      g_ks->gemm(g, 0, m, 0, panels);
    }
    benchmark::DoNotOptimize(x0.data());
  }
  add_peak_counter(state, 2.0 * m * n * k * count);
}

// The same LINEAR shapes in int8 (u8 activations x s8 weights, int32
// accumulation, fp32 epilogue; kernels/gemm/qs8_gemm.h), the best int8
// table this CPU runs. Counter GOP/s (2 M N K per call) and, beside BM_Gemm's
// GFLOP/s on the same shape, the int8 speed-up.
void BM_QGemm(benchmark::State& state) {
  const QKernelSet* qs = g_qs;
  if (!qs) {
    state.SkipWithError("no int8 kernels for this CPU");
    return;
  }
  const int m = int(state.range(0)), n = int(state.range(1)), k = int(state.range(2));
  std::mt19937 rng(3);
  std::vector<uint8_t> a(size_t(m) * k);
  for (uint8_t& v : a) v = uint8_t(rng());
  std::vector<int8_t> w(size_t(n) * k), packed(qs8_pack_w_bytes(n, k, qs->nr, qs->kgroup));
  for (int8_t& v : w) v = int8_t(int(rng() % 255) - 127);
  qs8_pack_w(n, k, qs->nr, qs->kgroup, w.data(), packed.data());
  std::vector<int32_t> colsum(n);
  qs8_column_sums(n, k, w.data(), colsum.data());
  const auto mult = rnd(n), bias = rnd(n);
  Buf c(size_t(m) * n);
  const QGemmArgs g{m,
                    n,
                    k,
                    a.data(),
                    size_t(k),
                    17,
                    packed.data(),
                    colsum.data(),
                    mult.data(),
                    bias.data(),
                    nullptr,
                    0,
                    c.data(),
                    size_t(n),
                    Act::kNone};
  const int panels = (n + qs->nr - 1) / qs->nr;
  for (auto _ : state) {
    qs->gemm(g, 0, m, 0, panels);
    benchmark::DoNotOptimize(c.data());
  }
  state.counters["GOP/s"] =
      benchmark::Counter(2.0 * m * n * k / 1e9, benchmark::Counter::kIsIterationInvariantRate);
  state.SetLabel(qs->isa);
}

// The transformer's shapes at 224 (784 / 196 tokens) and 128 (256 / 64), and
// the backbone's largest pointwise convolutions.
void gemm_shapes(benchmark::internal::Benchmark* b) {
  for (const auto& mnk : std::vector<std::vector<int64_t>>{{784, 256, 256},
                                                           {784, 512, 256},
                                                           {196, 256, 256},
                                                           {256, 256, 256},
                                                           {64, 256, 256},
                                                           {12544, 96, 16},
                                                           {12544, 16, 32},
                                                           {3136, 40, 144},
                                                           {3136, 144, 24},
                                                           {784, 240, 40},
                                                           {196, 480, 80},
                                                           {1, 1024, 256}}) {
    b->Args(mnk);
  }
}
BENCHMARK(BM_Gemm)->Apply(gemm_shapes);
BENCHMARK(BM_QGemm)->Apply(gemm_shapes);
BENCHMARK(BM_GemmChain)->Args({784, 256, 256, 36})->Args({196, 256, 256, 36});

}  // namespace aprt::kernels::bench
