// Input preprocessing: a camera frame to the network input, and the LiDAR
// inputs (farthest-point sampling, the BEV histogram).
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <random>
#include <vector>

#include "kernels/preprocess/lidar__ref.h"
#include "kernels/preprocess/lidar_fast.h"
#include "kernels/preprocess/preprocess_image.h"
#include "kernels/preprocess/u8_f32_preprocess__ref.h"
#include "kernels/table/kernel_table.h"
#include "tests/kernels/bench_support.h"

namespace aprt::kernels::bench {

// A 640x480 camera frame to the network input: the reference (per-pixel
// arithmetic as written), the portable table-driven loop, and this ISA's
// kernel. Args: pixel format (0 RGB24, 2 YUYV, 4 NV12), output size,
// variant (0 reference, 1 portable, 2 ISA). Counter: output pixels per second.
void BM_Preprocess(benchmark::State& state) {
  const auto f = PixelFormat(state.range(0));
  const int size = int(state.range(1)), variant = int(state.range(2));
  const int w = 640, h = 480;
  std::vector<uint8_t> frame(frame_bytes(f, w, h));
  std::mt19937 rng(5);
  for (uint8_t& b : frame) b = uint8_t(rng());
  const ImageView img{frame.data(), f, w, h, min_stride(f, w)};
  const PreprocessParams p{size, 3, {0.485f, 0.456f, 0.406f}, {0.229f, 0.224f, 0.225f}};
  auto plan = std::make_unique<PreprocessPlan>();
  plan_preprocess(p, f, w, h, plan.get(), variant == 2 ? g_ks->preprocess : nullptr);
  Buf out(size_t(size) * size * 3);
  for (auto _ : state) {
    if (variant == 0) {
      u8_f32_preprocess__ref(img, p, out.data());
    } else if (variant == 1) {
      preprocess_image_portable(*plan, img, out.data());
    } else {
      preprocess_image(*plan, img, out.data());
    }
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["Mpix/s"] =
      benchmark::Counter(double(size) * size / 1e6, benchmark::Counter::kIsIterationInvariantRate);
  static const char* const kVariant[] = {"reference", "portable", nullptr};
  state.SetLabel(std::string(pixel_format_name(f)) + " " +
                 (variant == 2 ? g_ks->isa : kVariant[variant]));
}

BENCHMARK(BM_Preprocess)
    ->ArgsProduct({{int(PixelFormat::kRgb24), int(PixelFormat::kYuyv), int(PixelFormat::kNv12)},
                   {64, 224},
                   {0, 1, 2}})
    ->Unit(benchmark::kMicrosecond);

// LiDAR preprocessing (issue #5): farthest-point sampling of Arg(1) of
// Arg(0) points, and the BEV histogram of Arg(0) points on 256 x 256 cells;
// Arg(2): 0 reference, 1 fast. Random points in a 80 m square.
std::vector<LidarPoint> bench_scan(size_t n) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> xy(-40.0f, 40.0f), z(-3.0f, 8.0f);
  std::vector<LidarPoint> p(n);
  for (LidarPoint& q : p) q = {xy(rng), xy(rng), z(rng), 0.0f};
  return p;
}

void BM_LidarFps(benchmark::State& state) {
  const size_t n = size_t(state.range(0)), count = size_t(state.range(1));
  const auto p = bench_scan(n);
  std::vector<uint32_t> idx(count);
  std::vector<float> scratch(4 * n);
  for (auto _ : state) {
    if (state.range(2) == 0) {
      lidar_fps__ref(p.data(), n, count, idx.data(), scratch.data());
    } else {
      lidar_fps(p.data(), n, count, idx.data(), scratch.data());
    }
    benchmark::DoNotOptimize(idx.data());
  }
  state.SetLabel(state.range(2) == 0 ? "reference" : "fast");
}

BENCHMARK(BM_LidarFps)
    ->Args({20000, 1024, 0})
    ->Args({20000, 1024, 1})
    ->Args({20000, 4096, 0})
    ->Args({20000, 4096, 1})
    ->Unit(benchmark::kMillisecond);

void BM_LidarBev(benchmark::State& state) {
  const size_t n = size_t(state.range(0));
  const auto p = bench_scan(n);
  const BevParams b{256, 0.125f, -16.0f, -16.0f, 0.2f, 5.0f};
  std::vector<float> out(256 * 256 * 2);
  std::vector<uint16_t> counts(out.size());
  for (auto _ : state) {
    if (state.range(1) == 0) {
      lidar_bev_histogram__ref(p.data(), n, b, out.data());
    } else {
      lidar_bev_histogram(p.data(), n, b, counts.data(), out.data());
    }
    benchmark::DoNotOptimize(out.data());
  }
  state.SetLabel(state.range(1) == 0 ? "reference" : "fast");
}

BENCHMARK(BM_LidarBev)->Args({120000, 0})->Args({120000, 1})->Unit(benchmark::kMicrosecond);

}  // namespace aprt::kernels::bench
