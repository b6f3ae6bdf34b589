// The depthwise convolutions of EfficientNet-B0, fp32 and int8.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "kernels/dwconv/qu8s8_dwconv2d.h"
#include "kernels/table/kernel_table.h"
#include "tests/kernels/bench_support.h"

namespace aprt::kernels::bench {

void BM_Depthwise(benchmark::State& state) {
  const int hw = int(state.range(0)), c = int(state.range(1)), kk = int(state.range(2)),
            s = int(state.range(3));
  const int pad = (kk - 1) / 2;
  const int out = (hw + 2 * pad - kk) / s + 1;
  const Conv2dShape sh{hw, hw, c, out, out, c, kk, kk, s, s, pad, pad};
  const auto x = rnd(size_t(hw) * hw * c), w = rnd(size_t(kk) * kk * c), b = rnd(c);
  Buf y(size_t(out) * out * c);
  for (auto _ : state) {
    g_ks->dwconv_rows(sh, x.data(), w.data(), b.data(), Act::kSilu, y.data(), 0, out);
    benchmark::DoNotOptimize(y.data());
  }
  add_peak_counter(state, 2.0 * out * out * c * kk * kk);
}

// The same convolutions in int8 (kernels/dwconv/qu8s8_dwconv2d_impl.inl): the input
// quantised (as the op does each frame) plus the convolution, against
// BM_Depthwise's fp32 time on the same shape.
void BM_QDepthwise(benchmark::State& state) {
  if (!g_qs) {
    state.SkipWithError("no int8 kernels for this CPU");
    return;
  }
  const int hw = int(state.range(0)), c = int(state.range(1)), kk = int(state.range(2)),
            s = int(state.range(3));
  const int pad = (kk - 1) / 2;
  const int out = (hw + 2 * pad - kk) / s + 1;
  const Conv2dShape sh{hw, hw, c, out, out, c, kk, kk, s, s, pad, pad};
  const auto x = rnd(size_t(hw) * hw * c), w = rnd(size_t(kk) * kk * c), b = rnd(c), m = rnd(c);
  std::vector<uint8_t> q(x.size());
  Buf y(size_t(out) * out * c);
  const QDwConvArgs a{sh, q.data(), 128, w.data(), m.data(), b.data(), Act::kSilu, y.data()};
  for (auto _ : state) {
    g_qs->quantize(x.size(), x.data(), 40.0f, 128, q.data());
    g_qs->dwconv_rows(a, 0, out);
    benchmark::DoNotOptimize(y.data());
  }
  add_peak_counter(state, 2.0 * out * out * c * kk * kk);
  state.SetLabel(g_qs->isa);
}

BENCHMARK(BM_Depthwise)
    ->Args({112, 96, 3, 2})
    ->Args({56, 144, 5, 2})
    ->Args({28, 240, 3, 2})
    ->Args({14, 480, 5, 1});

BENCHMARK(BM_QDepthwise)
    ->Args({112, 96, 3, 2})
    ->Args({56, 144, 5, 2})
    ->Args({28, 240, 3, 2})
    ->Args({14, 480, 5, 1});

}  // namespace aprt::kernels::bench
