// PointNet++ ops at the full 'points' configuration's first level (4096
// points, 1024 centres, radius 0.1, 32 neighbours, 6 features) and its last
// propagation (1024 targets from 256 known, 256 channels); points in [-1, 1].
// Arg(0): 0 reference, 1 fast.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "kernels/points/pointnet__ref.h"
#include "kernels/points/pointnet_fast.h"
#include "tests/kernels/bench_support.h"

namespace aprt::kernels::bench {

std::vector<float> bench_rows(size_t n, size_t stride) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<float> x(n * stride);
  for (float& v : x) v = u(rng);
  return x;
}

void BM_PointFps(benchmark::State& state) {
  const size_t n = 4096, count = 1024;
  const auto p = bench_rows(n, 6);
  std::vector<uint32_t> idx(count);
  std::vector<float> dist(n), soa(3 * n);
  for (auto _ : state) {
    if (state.range(0) == 0) {
      f32_fps__ref(p.data(), 6, n, count, idx.data(), dist.data());
    } else {
      f32_points_to_soa(p.data(), 6, n, soa.data());
      f32_fps_soa(soa.data(), n, count, idx.data(), dist.data());
    }
    benchmark::DoNotOptimize(idx.data());
  }
  state.SetLabel(state.range(0) == 0 ? "reference" : "fast");
}

BENCHMARK(BM_PointFps)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

void BM_BallGroup(benchmark::State& state) {
  const size_t n = 4096;
  const int s = 1024, k = 32, c = 6;
  const auto p = bench_rows(n, 6);
  std::vector<float> centres(p.begin(), p.begin() + size_t(s) * 6);  // points of the cloud
  std::vector<float> y(size_t(s) * k * (3 + c)), soa(3 * n);
  for (auto _ : state) {
    if (state.range(0) == 0) {
      f32_ball_group__ref(p.data(), 6, n, centres.data(), 6, 0, s, 0.1f, k, p.data(), c, y.data());
    } else {
      f32_points_to_soa(p.data(), 6, n, soa.data());
      f32_ball_group_soa(soa.data(), n, centres.data(), 6, 0, s, 0.1f, k, p.data(), c, y.data());
    }
    benchmark::DoNotOptimize(y.data());
  }
  state.SetLabel(state.range(0) == 0 ? "reference" : "fast");
}

BENCHMARK(BM_BallGroup)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

void BM_ThreeInterp(benchmark::State& state) {
  const size_t nk = 256;
  const int nt = 1024, c = 256;
  const auto known = bench_rows(nk, 3);
  const auto targets = bench_rows(size_t(nt), 3);
  const auto feats = bench_rows(nk, size_t(c));
  std::vector<float> y(size_t(nt) * c), soa(3 * nk), dist(nk);
  for (auto _ : state) {
    if (state.range(0) == 0) {
      f32_three_interp__ref(targets.data(), 3, 0, nt, known.data(), 3, nk, feats.data(), c,
                            y.data());
    } else {
      f32_points_to_soa(known.data(), 3, nk, soa.data());
      f32_three_interp_soa(targets.data(), 3, 0, nt, soa.data(), nk, feats.data(), c, y.data(),
                           dist.data());
    }
    benchmark::DoNotOptimize(y.data());
  }
  state.SetLabel(state.range(0) == 0 ? "reference" : "fast");
}

BENCHMARK(BM_ThreeInterp)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

void BM_GroupMax(benchmark::State& state) {
  const int s = 1024, k = 32, c = 64;
  const auto x = bench_rows(size_t(s) * k, size_t(c));
  std::vector<float> y(size_t(s) * c);
  for (auto _ : state) {
    if (state.range(0) == 0) {
      f32_group_max__ref(k, c, x.data(), y.data(), 0, s);
    } else {
      f32_group_max(k, c, x.data(), y.data(), 0, s);
    }
    benchmark::DoNotOptimize(y.data());
  }
  state.SetLabel(state.range(0) == 0 ? "reference" : "fast");
}

BENCHMARK(BM_GroupMax)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

}  // namespace aprt::kernels::bench
