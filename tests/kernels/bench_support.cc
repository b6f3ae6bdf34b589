// kernels_bench's main: picks the kernel table (--isa), measures the FMA peak
// the families' "peak%" counters refer to, runs Google Benchmark.
#include "tests/kernels/bench_support.h"

#if defined(__x86_64__)
#include <xmmintrin.h>
#endif

#include <cstdio>
#include <cstring>
#include <random>
#include <string>

#include "tools/bench/fma_peak.h"

namespace aprt::kernels::bench {

const KernelSet* g_ks = nullptr;
const QKernelSet* g_qs = nullptr;
const Bf16AttentionKernels* g_bf = nullptr;
double g_peak_gflops = 0.0;

Buf rnd(size_t n) {
  std::mt19937 g(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  Buf v(n);
  for (auto& x : v) x = u(g);
  return v;
}

void add_peak_counter(benchmark::State& state, double flops_per_iter) {
  using C = benchmark::Counter;
  state.counters["GFLOP/s"] = C(flops_per_iter / 1e9, C::kIsIterationInvariantRate);
  state.counters["peak%"] =
      C(flops_per_iter / 1e9 * 100.0 / g_peak_gflops, C::kIsIterationInvariantRate);
  state.SetLabel(g_ks->isa);
}

namespace {

void BM_FmaPeak(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(aprt::bench::fma_peak_gflops(20'000'000));
  state.counters["GFLOP/s"] = g_peak_gflops;
}
BENCHMARK(BM_FmaPeak)->Iterations(1);

void set_flush_denormals() {
#if defined(__x86_64__)
  _mm_setcsr(_mm_getcsr() | 0x8040u);
#endif
}

}  // namespace
}  // namespace aprt::kernels::bench

int main(int argc, char** argv) {
  using namespace aprt::kernels::bench;
  set_flush_denormals();  // as Engine::run() does
  const char* isa = "auto";
  for (int i = 1; i < argc; ++i) {
    if (std::strncmp(argv[i], "--isa=", 6) == 0) isa = argv[i] + 6;
  }
  auto table = aprt::kernels::pick_kernels(isa);
  if (!table || !table->f32) {
    std::fprintf(stderr, "kernels_bench: no fast kernels for '%s' on this CPU%s%s\n", isa,
                 table ? "" : ": ", table ? "" : table.error().message());
    return 2;
  }
  g_ks = table->f32;
  g_qs = table->qs8;
  g_bf = table->bf16;
  g_peak_gflops = aprt::bench::fma_peak_gflops(400'000'000);
  std::printf("FMA peak of one core, measured now: %.1f GFLOP/s (%s kernels)\n", g_peak_gflops,
              g_ks->isa);
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
