// Row-wise kernels: LayerNorm over the transformers' token rows, activations.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "kernels/table/kernel_table.h"
#include "tests/kernels/bench_support.h"

namespace aprt::kernels::bench {

// LAYERNORM over rows x width (the transformers' 784 / 196 tokens of 256).
void BM_LayerNorm(benchmark::State& state) {
  const int rows = int(state.range(0)), n = int(state.range(1));
  const auto x = rnd(size_t(rows) * n), gamma = rnd(n), beta = rnd(n);
  Buf y(x.size());
  for (auto _ : state) {
    g_ks->layernorm_rows(n, x.data(), gamma.data(), beta.data(), 1e-5f, y.data(), 0, rows);
    benchmark::DoNotOptimize(y.data());
  }
  state.counters["Gelem/s"] =
      benchmark::Counter(double(rows) * n / 1e9, benchmark::Counter::kIsIterationInvariantRate);
  state.SetLabel(g_ks->isa);
}

BENCHMARK(BM_LayerNorm)->Args({784, 256})->Args({196, 256});

void BM_Activation(benchmark::State& state) {
  const auto x = rnd(65536);
  Buf y(x.size());
  for (auto _ : state) {
    g_ks->activation(Act(state.range(0)), x.data(), y.data(), 0, x.size());
    benchmark::DoNotOptimize(y.data());
  }
  state.counters["Gelem/s"] =
      benchmark::Counter(65536.0 / 1e9, benchmark::Counter::kIsIterationInvariantRate);
  state.SetLabel(g_ks->isa);
}

BENCHMARK(BM_Activation)->Arg(1)->Arg(2)->Arg(3);

}  // namespace aprt::kernels::bench
