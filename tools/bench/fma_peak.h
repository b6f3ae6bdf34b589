// The FMA throughput of one core, measured with the widest vectors it has:
// 16 independent fused multiply-add chains, enough to hide the latency.
#pragma once

namespace aprt::bench {

double fma_peak_gflops(long iterations);

}  // namespace aprt::bench
