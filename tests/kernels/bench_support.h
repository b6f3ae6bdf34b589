// What the kernel families' benchmarks (tests/kernels/<family>/*_bench.cc,
// one kernels_bench binary) share: the kernel table picked by --isa, the
// FMA peak measured at start-up, aligned random buffers.
//   build/release/bin/kernels_bench [--isa=avx512|avx2|neon] [--benchmark_filter=...]
#pragma once

#include <benchmark/benchmark.h>

#include <cstddef>
#include <cstdlib>
#include <vector>

#include "kernels/table/kernel_table.h"

namespace aprt::kernels::bench {

extern const KernelSet* g_ks;             // fp32: the table --isa picks
extern const QKernelSet* g_qs;            // int8: the part that goes with it
extern const Bf16AttentionKernels* g_bf;  // bf16 attention, or null on this CPU
extern double g_peak_gflops;              // one core's FMA peak, measured now

// 64-byte aligned like the engine's arena and packed weights.
template <class T>
struct Aligned64 {
  using value_type = T;
  Aligned64() = default;
  template <class U>
  Aligned64(const Aligned64<U>&) {}
  T* allocate(size_t n) {
    return static_cast<T*>(std::aligned_alloc(64, (n * sizeof(T) + 63) / 64 * 64));
  }
  void deallocate(T* p, size_t) { std::free(p); }
  bool operator==(const Aligned64&) const { return true; }
  bool operator!=(const Aligned64&) const { return false; }
};
using Buf = std::vector<float, Aligned64<float>>;

// n values uniform in [-1, 1], the same every call.
Buf rnd(size_t n);
// Counters GFLOP/s and the share of the FMA peak ("peak%"); label: the ISA.
void add_peak_counter(benchmark::State& state, double flops_per_iter);

}  // namespace aprt::kernels::bench
