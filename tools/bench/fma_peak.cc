#include "tools/bench/fma_peak.h"

#include <chrono>

#include "kernels/table/cpu_features.h"

namespace aprt::bench {

float fma_chains_avx512(long iterations);  // 16 x 16-lane chains; returns a sum
float fma_chains_avx2(long iterations);    // 16 x 8-lane chains
float fma_chains_neon(long iterations);    // 16 x 4-lane chains

double fma_peak_gflops(long iterations) {
  const auto& cpu = kernels::cpu_features();
  int lanes = 0;
  float (*chains)(long) = nullptr;
#if defined(__x86_64__)
  if (cpu.avx512) {
    chains = fma_chains_avx512;
    lanes = 16;
  } else if (cpu.avx2_fma) {
    chains = fma_chains_avx2;
    lanes = 8;
  }
#elif defined(__aarch64__)
  if (cpu.neon) {
    chains = fma_chains_neon;
    lanes = 4;
  }
#endif
  if (!chains) return 0.0;
  chains(iterations / 10);  // wake the core up
  const auto t0 = std::chrono::steady_clock::now();
  volatile float sink = chains(iterations);
  (void)sink;
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return 2.0 * lanes * 16.0 * double(iterations) / s / 1e9;
}

}  // namespace aprt::bench
