// Google Benchmark of the fast kernels on the model's shapes, reported in
// GFLOP/s and as a share of this machine's FMA peak measured in the same run
// (counter "peak%"). Usage: build/release/bin/kernels_bench [--isa=avx512|avx2]
#include <benchmark/benchmark.h>

#if defined(__x86_64__)
#include <xmmintrin.h>
#endif

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "kernels/common/bf16_attention.h"
#include "kernels/common/cpu_features.h"
#include "kernels/common/kernel_set.h"
#include "kernels/common/lidar_fast.h"
#include "kernels/common/pointnet_fast.h"
#include "kernels/common/preprocess_image.h"
#include "kernels/common/qkernel_set.h"
#include "kernels/ref/lidar__ref.h"
#include "kernels/ref/pointnet__ref.h"
#include "kernels/ref/preprocess_image__ref.h"
#include "tools/bench/fma_peak.h"

namespace {

using namespace aprt::kernels;

const KernelSet* g_ks = nullptr;
const QKernelSet* g_qs = nullptr;  // int8: the table matching --isa
double g_peak_gflops = 0.0;

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

Buf rnd(size_t n) {
  std::mt19937 g(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  Buf v(n);
  for (auto& x : v) x = u(g);
  return v;
}

// GFLOP/s and the share of the FMA peak measured at start-up.
void add_peak_counter(benchmark::State& state, double flops_per_iter) {
  using C = benchmark::Counter;
  state.counters["GFLOP/s"] = C(flops_per_iter / 1e9, C::kIsIterationInvariantRate);
  state.counters["peak%"] =
      C(flops_per_iter / 1e9 * 100.0 / g_peak_gflops, C::kIsIterationInvariantRate);
  state.SetLabel(g_ks->isa);
}

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
// accumulation, fp32 epilogue; kernels/common/qkernel_set.h), the best int8
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

// Fused attention: Lq = Lk = L, heads x d, one thread.
void BM_Attention(benchmark::State& state) {
  const int l = int(state.range(0)), heads = int(state.range(1)), d = int(state.range(2));
  const int e = heads * d;
  const auto q = rnd(size_t(l) * e), k = rnd(size_t(l) * e), v = rnd(size_t(l) * e);
  const int lk_pad = (l + g_ks->attn_key_block - 1) / g_ks->attn_key_block * g_ks->attn_key_block;
  Buf kt(size_t(e) * lk_pad), vp(size_t(e) * lk_pad), o(size_t(l) * e),
      scratch(g_ks->attn_scratch(d));
  for (auto _ : state) {
    for (int h = 0; h < heads; ++h) {
      g_ks->attn_pack_kv(l, lk_pad, d, k.data(), size_t(e), v.data(), size_t(e), h, kt.data(),
                         vp.data());
    }
    for (int h = 0; h < heads; ++h) {
      for (int q0 = 0; q0 < l; q0 += g_ks->attn_max_rows) {
        const int rows = l - q0 < g_ks->attn_max_rows ? l - q0 : g_ks->attn_max_rows;
        g_ks->attn_block(rows, l, d, q.data(), size_t(e), kt.data(), vp.data(), lk_pad, 0.17f,
                         o.data(), size_t(e), h, q0, scratch.data());
      }
    }
    benchmark::DoNotOptimize(o.data());
  }
  add_peak_counter(state, 4.0 * l * l * e);
}

// The same attention with int8 scores (kernels/common/qs8_attention.h): Q and
// K quantised per row and head, the int8 table's kernel; "GFLOP/s" counts the
// fp32 attention's flops, so it compares with BM_Attention directly.
void BM_QAttention(benchmark::State& state) {
  const QKernelSet* qs = g_qs;
  if (!qs || !qs->attn_block) {
    state.SkipWithError("no int8-score attention for this CPU");
    return;
  }
  const int l = int(state.range(0)), heads = int(state.range(1)), d = int(state.range(2));
  const int e = heads * d;
  const auto q = rnd(size_t(l) * e), k = rnd(size_t(l) * e), v = rnd(size_t(l) * e);
  const int lk_pad = (l + qs->attn_key_block - 1) / qs->attn_key_block * qs->attn_key_block;
  std::vector<uint8_t> kq(qs->attn_kq_bytes(heads, lk_pad, d));
  Buf vp(size_t(e) * lk_pad), o(size_t(l) * e), scratch(qs->attn_scratch(d));
  for (auto _ : state) {
    for (int h = 0; h < heads; ++h) {
      qs->attn_pack_kv(l, lk_pad, d, k.data(), size_t(e), v.data(), size_t(e), h, kq.data(),
                       vp.data());
    }
    for (int h = 0; h < heads; ++h) {
      for (int q0 = 0; q0 < l; q0 += qs->attn_max_rows) {
        const int rows = l - q0 < qs->attn_max_rows ? l - q0 : qs->attn_max_rows;
        qs->attn_block(rows, l, d, q.data(), size_t(e), kq.data(), vp.data(), lk_pad, 0.17f,
                       o.data(), size_t(e), h, q0, scratch.data());
      }
    }
    benchmark::DoNotOptimize(o.data());
  }
  add_peak_counter(state, 4.0 * l * l * e);
  state.SetLabel(qs->isa);
}

// The same attention in bf16 (kernels/common/bf16_attention.h): Q, K, V and
// the weights rounded to bf16, vdpbf16ps for both products; "GFLOP/s" again
// counts the fp32 attention's flops against the fp32 FMA peak.
void BM_Bf16Attention(benchmark::State& state) {
  const Bf16AttentionKernels* bk = bf16_attention_avx512bf16();
  if (!bk || !cpu_features().avx512_bf16 || std::string(g_ks->isa) != "avx512") {
    state.SkipWithError("no bf16 attention for this CPU / ISA");
    return;
  }
  const int l = int(state.range(0)), heads = int(state.range(1)), d = int(state.range(2));
  const int e = heads * d;
  const auto q = rnd(size_t(l) * e), k = rnd(size_t(l) * e), v = rnd(size_t(l) * e);
  const int lk_pad = (l + bk->key_block - 1) / bk->key_block * bk->key_block;
  std::vector<uint16_t> kv(bk->kv_bytes(heads, lk_pad, d) / 2);
  Buf o(size_t(l) * e), scratch(bk->scratch(d));
  for (auto _ : state) {
    for (int h = 0; h < heads; ++h)
      bk->pack_kv(l, lk_pad, d, k.data(), size_t(e), v.data(), size_t(e), h, kv.data());
    for (int h = 0; h < heads; ++h) {
      for (int q0 = 0; q0 < l; q0 += bk->max_rows) {
        const int rows = l - q0 < bk->max_rows ? l - q0 : bk->max_rows;
        bk->block(rows, l, d, q.data(), size_t(e), kv.data(), lk_pad, 0.17f, o.data(), size_t(e), h,
                  q0, scratch.data());
      }
    }
    benchmark::DoNotOptimize(o.data());
  }
  add_peak_counter(state, 4.0 * l * l * e);
  state.SetLabel(bk->isa);
}

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

// The same convolutions in int8 (kernels/simd/qdwconv_impl.inl): the input
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

void BM_FmaPeak(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(aprt::bench::fma_peak_gflops(20'000'000));
  state.counters["GFLOP/s"] = g_peak_gflops;
}

void set_flush_denormals() {
#if defined(__x86_64__)
  _mm_setcsr(_mm_getcsr() | 0x8040u);
#endif
}

}  // namespace

// The transformer's shapes at 224 (784 / 196 tokens) and 128 (256 / 64), and
// the backbone's largest pointwise convolutions.
BENCHMARK(BM_FmaPeak)->Iterations(1);
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
BENCHMARK(BM_Attention)
    ->Args({784, 8, 32})
    ->Args({256, 8, 32})
    ->Args({196, 8, 32})
    ->Args({64, 8, 32});
BENCHMARK(BM_QAttention)->Args({784, 8, 32})->Args({196, 8, 32});
BENCHMARK(BM_Bf16Attention)->Args({784, 8, 32})->Args({196, 8, 32});
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
      preprocess_image__ref(img, p, out.data());
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

// PointNet++ ops at the full 'points' configuration's first level (4096
// points, 1024 centres, radius 0.1, 32 neighbours, 6 features) and its last
// propagation (1024 targets from 256 known, 256 channels); points in [-1, 1].
// Arg(0): 0 reference, 1 fast.
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

int main(int argc, char** argv) {
  set_flush_denormals();  // as Engine::run() does
  std::string isa = "auto";
  for (int i = 1; i < argc; ++i) {
    if (std::strncmp(argv[i], "--isa=", 6) == 0) isa = argv[i] + 6;
  }
  const auto& cpu = cpu_features();
  if ((isa == "auto" || isa == "avx512") && cpu.avx512)
    g_ks = kernel_set_avx512();
  else if ((isa == "auto" || isa == "avx2") && cpu.avx2_fma)
    g_ks = kernel_set_avx2();
  else if ((isa == "auto" || isa == "neon") && cpu.neon)
    g_ks = kernel_set_neon();
  if (!g_ks) {
    std::fprintf(stderr, "kernels_bench: no fast kernels for '%s' on this CPU\n", isa.c_str());
    return 2;
  }
  g_qs = std::string(g_ks->isa) == "avx2" ? qkernel_set_avx2() : qkernel_set_best();
  g_peak_gflops = aprt::bench::fma_peak_gflops(400'000'000);
  std::printf("FMA peak of one core, measured now: %.1f GFLOP/s (%s kernels)\n", g_peak_gflops,
              g_ks->isa);
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
