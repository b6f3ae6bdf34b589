// Every fast kernel against its reference, on random odd shapes, for every
// ISA this CPU can run (the others are skipped, and say so).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "kernels/common/cpu_features.h"
#include "kernels/common/kernel_set.h"
#include "kernels/ref/f32_attention__ref.h"
#include "kernels/ref/f32_conv2d__ref.h"
#include "kernels/ref/f32_cross_attention_1q__ref.h"
#include "kernels/ref/f32_dwconv2d__ref.h"
#include "kernels/ref/f32_elementwise__ref.h"
#include "kernels/ref/f32_layernorm__ref.h"
#include "kernels/ref/f32_linear__ref.h"
#include "kernels/ref/f32_squeeze_excite__ref.h"
#include "kernels/ref/preprocess_image__ref.h"

namespace aprt::kernels {
namespace {

struct IsaCase {
  const char* name;
  const KernelSet* (*get)();
  bool (*supported)();
};

const IsaCase kIsas[] = {
    {"avx512", kernel_set_avx512, [] { return cpu_features().avx512; }},
    {"avx2", kernel_set_avx2, [] { return cpu_features().avx2_fma; }},
    {"neon", kernel_set_neon, [] { return cpu_features().neon; }},
};

class FastKernels : public ::testing::TestWithParam<IsaCase> {
 protected:
  void SetUp() override {
    ks_ = GetParam().get();
    if (!ks_) GTEST_SKIP() << GetParam().name << " is not part of this build";
    if (!GetParam().supported()) GTEST_SKIP() << "this CPU cannot run " << GetParam().name;
  }
  const KernelSet* ks_ = nullptr;
  std::mt19937 rng_{12345};

  std::vector<float> rnd(size_t n, float s = 1.0f) {
    std::uniform_real_distribution<float> u(-s, s);
    std::vector<float> v(n);
    for (auto& x : v) x = u(rng_);
    return v;
  }
  int pick(int lo, int hi) { return lo + int(rng_() % unsigned(hi - lo + 1)); }
};

void expect_near_all(const std::vector<float>& got, const std::vector<float>& want, double tol,
                     const std::string& what) {
  ASSERT_EQ(got.size(), want.size());
  for (size_t i = 0; i < got.size(); ++i) {
    ASSERT_NEAR(got[i], want[i], tol * (1.0 + std::fabs(want[i]))) << what << " at " << i;
  }
}

TEST_P(FastKernels, GemmWithPackedWeights) {
  for (int round = 0; round < 60; ++round) {
    const int m = pick(1, 40), n = pick(1, 3 * ks_->gemm_nr + 5), k = pick(1, 300);
    const Act act = Act(pick(0, 4));
    const bool with_bias = pick(0, 1), with_res = pick(0, 1);
    const auto x = rnd(size_t(m) * k), w = rnd(size_t(n) * k, 0.3f), b = rnd(n),
               r = rnd(size_t(m) * n);
    std::vector<float> want(size_t(m) * n), got(size_t(m) * n, -7.0f);
    f32_linear__ref({m, n, k}, x.data(), w.data(), with_bias ? b.data() : nullptr,
                    with_res ? r.data() : nullptr, act, want.data());
    std::vector<float> packed(f32_pack_b_floats(n, k, ks_->gemm_nr));
    f32_pack_b(n, k, ks_->gemm_nr, w.data(), packed.data());
    GemmArgs g{m,
               n,
               k,
               x.data(),
               size_t(k),
               packed.data(),
               size_t(ks_->gemm_nr),
               size_t(k) * ks_->gemm_nr,
               true,
               with_bias ? b.data() : nullptr,
               with_res ? r.data() : nullptr,
               size_t(n),
               got.data(),
               size_t(n),
               act};
    // Cover the output in two uneven row ranges and two panel ranges, as threads do.
    const int panels = (n + ks_->gemm_nr - 1) / ks_->gemm_nr;
    const int rs = pick(0, m), ps = pick(0, panels);
    ks_->gemm(g, 0, rs, 0, ps);
    ks_->gemm(g, rs, m, 0, ps);
    ks_->gemm(g, 0, rs, ps, panels);
    ks_->gemm(g, rs, m, ps, panels);
    expect_near_all(
        got, want, 2e-5,
        "gemm m=" + std::to_string(m) + " n=" + std::to_string(n) + " k=" + std::to_string(k));
  }
}

TEST_P(FastKernels, GemmWithRowMajorB) {
  for (int round = 0; round < 40; ++round) {
    const int m = pick(1, 20), n = pick(1, 2 * ks_->gemm_nr + 7), k = pick(1, 200);
    const auto x = rnd(size_t(m) * k), w = rnd(size_t(n) * k);
    // B = W^T as a plain [k][n] matrix, exactly sized (the tail panel must not over-read).
    std::vector<float> bt(size_t(k) * n);
    for (int j = 0; j < n; ++j)
      for (int p = 0; p < k; ++p) bt[size_t(p) * n + j] = w[size_t(j) * k + p];
    std::vector<float> want(size_t(m) * n), got(size_t(m) * n);
    f32_linear__ref({m, n, k}, x.data(), w.data(), nullptr, nullptr, Act::kNone, want.data());
    GemmArgs g{
        m,     n,       k,       x.data(), size_t(k),  bt.data(), size_t(n), size_t(ks_->gemm_nr),
        false, nullptr, nullptr, 0,        got.data(), size_t(n), Act::kNone};
    ks_->gemm(g, 0, m, 0, (n + ks_->gemm_nr - 1) / ks_->gemm_nr);
    expect_near_all(got, want, 2e-5, "gemm row-major B");
  }
}

TEST_P(FastKernels, DepthwiseConvolution) {
  for (int round = 0; round < 60; ++round) {
    const int k = round % 3 == 0 ? 3 : (round % 3 == 1 ? 5 : pick(1, 7));
    const int s = pick(1, 2), h = pick(1, 13), w = pick(1, 29), c = pick(1, 70);
    const int pt = pick(0, k - 1), pl = pick(0, k - 1), pb = pick(0, k - 1), pr = pick(0, k - 1);
    if (h + pt + pb < k || w + pl + pr < k) continue;
    const Conv2dShape sh{h, w,  c, (h + pt + pb - k) / s + 1, (w + pl + pr - k) / s + 1, c, k, k, s,
                         s, pt, pl};
    const auto x = rnd(size_t(h) * w * c), wt = rnd(size_t(k) * k * c), b = rnd(c);
    const Act act = Act(pick(0, 4));
    std::vector<float> want(size_t(sh.out_h) * sh.out_w * c), got(want.size());
    f32_dwconv2d__ref(sh, x.data(), wt.data(), b.data(), act, want.data());
    const int split = pick(0, sh.out_h);
    ks_->dwconv_rows(sh, x.data(), wt.data(), b.data(), act, got.data(), 0, split);
    ks_->dwconv_rows(sh, x.data(), wt.data(), b.data(), act, got.data(), split, sh.out_h);
    expect_near_all(got, want, 2e-5, "dwconv k=" + std::to_string(k));
  }
}

TEST_P(FastKernels, DenseConvolution) {
  for (int round = 0; round < 40; ++round) {
    const int k = pick(0, 2) * 2 + 1, s = pick(1, 2), h = pick(1, 11), w = pick(1, 29);
    const int ci = pick(1, 5), co = pick(1, 80);
    const int pt = pick(0, k - 1), pl = pick(0, k - 1), pb = pick(0, k - 1), pr = pick(0, k - 1);
    if (h + pt + pb < k || w + pl + pr < k) continue;
    const Conv2dShape sh{
        h, w, ci, (h + pt + pb - k) / s + 1, (w + pl + pr - k) / s + 1, co, k, k, s, s, pt, pl};
    const auto x = rnd(size_t(h) * w * ci), wt = rnd(size_t(co) * k * k * ci), b = rnd(co);
    const auto res = rnd(size_t(sh.out_h) * sh.out_w * co);
    const Act act = Act(pick(0, 4));
    const bool with_res = pick(0, 1);
    std::vector<float> want(res.size()), got(res.size()), packed(wt.size());
    f32_conv2d__ref(sh, x.data(), wt.data(), b.data(), with_res ? res.data() : nullptr, act,
                    want.data());
    f32_conv2d_pack_weights(co, k, k, ci, wt.data(), packed.data());
    ks_->conv_rows(sh, x.data(), packed.data(), b.data(), with_res ? res.data() : nullptr, act,
                   got.data(), 0, sh.out_h);
    expect_near_all(got, want, 2e-5, "conv");
  }
}

// Widths of whole vector pairs on every ISA (multiples of 32) take the
// four-rows-interleaved path for each full group of four rows of a range:
// against the reference, and bit for bit against the one-row loop (a range
// of one row), which it claims to match operation for operation.
TEST_P(FastKernels, LayerNormFourRowsMatchOneRow) {
  for (int round = 0; round < 20; ++round) {
    const int rows = pick(4, 13), n = 32 * pick(1, 10);
    auto x = rnd(size_t(rows) * n, 3.0f);
    for (auto& v : x) v += 2.0f;
    const auto g = rnd(n), b = rnd(n);
    std::vector<float> want(x.size()), got(x.size()), one(x.size());
    f32_layernorm__ref(rows, n, x.data(), g.data(), b.data(), 1e-5f, want.data());
    const int r0 = pick(0, rows - 4);  // a range that starts anywhere
    ks_->layernorm_rows(n, x.data(), g.data(), b.data(), 1e-5f, got.data(), 0, r0);
    ks_->layernorm_rows(n, x.data(), g.data(), b.data(), 1e-5f, got.data(), r0, rows);
    for (int r = 0; r < rows; ++r) {
      ks_->layernorm_rows(n, x.data(), g.data(), b.data(), 1e-5f, one.data(), r, r + 1);
    }
    expect_near_all(got, want, 2e-5, "layernorm n=" + std::to_string(n));
    EXPECT_EQ(got, one) << "n=" << n << " rows=" << rows << " r0=" << r0;
  }
}

TEST_P(FastKernels, LayerNormAddActivation) {
  for (int round = 0; round < 30; ++round) {
    const int rows = pick(1, 9), n = pick(1, 300);
    auto x = rnd(size_t(rows) * n, 3.0f);
    for (auto& v : x) v += 2.0f;
    const auto g = rnd(n), b = rnd(n);
    std::vector<float> want(x.size()), got(x.size());
    f32_layernorm__ref(rows, n, x.data(), g.data(), b.data(), 1e-5f, want.data());
    ks_->layernorm_rows(n, x.data(), g.data(), b.data(), 1e-5f, got.data(), 0, rows);
    expect_near_all(got, want, 2e-5, "layernorm n=" + std::to_string(n));
    const auto y = rnd(x.size());
    f32_add__ref(x.size(), x.data(), y.data(), want.data());
    const size_t cut = size_t(pick(0, int(x.size())));
    ks_->add(x.data(), y.data(), got.data(), 0, cut);
    ks_->add(x.data(), y.data(), got.data(), cut, x.size());
    EXPECT_EQ(got, want);
    for (int act = 0; act <= 4; ++act) {
      f32_activation__ref(x.size(), Act(act), x.data(), want.data());
      ks_->activation(Act(act), x.data(), got.data(), 0, x.size());
      expect_near_all(got, want, 1e-6, "activation " + std::to_string(act));
    }
  }
}

TEST_P(FastKernels, ActivationsOverTheirWholeRange) {
  std::vector<float> x;
  for (float v = -100.0f; v <= 100.0f; v += 0.01f) x.push_back(v);
  std::vector<float> want(x.size()), got(x.size());
  for (int act = 1; act <= 3; ++act) {
    f32_activation__ref(x.size(), Act(act), x.data(), want.data());
    ks_->activation(Act(act), x.data(), got.data(), 0, x.size());
    for (size_t i = 0; i < x.size(); ++i) {
      ASSERT_NEAR(got[i], want[i], 3e-7 * (1.0 + std::fabs(want[i])))
          << "act " << act << " x " << x[i];
    }
  }
}

TEST_P(FastKernels, SqueezeExcite) {
  for (int round = 0; round < 20; ++round) {
    const int px = pick(1, 60), c = pick(1, 100), cr = pick(1, 30);
    const auto x = rnd(size_t(px) * c), w1 = rnd(size_t(cr) * c), b1 = rnd(cr),
               w2 = rnd(size_t(c) * cr), b2 = rnd(c);
    std::vector<float> want(x.size()), got(x.size()), scratch(size_t(c) + cr), gate(c),
        w2t(w2.size());
    for (int i = 0; i < c; ++i)
      for (int r = 0; r < cr; ++r) w2t[size_t(r) * c + i] = w2[size_t(i) * cr + r];
    f32_squeeze_excite__ref(px, c, cr, x.data(), w1.data(), b1.data(), w2.data(), b2.data(),
                            want.data(), scratch.data());
    ks_->se_gate(px, c, cr, x.data(), w1.data(), b1.data(), w2t.data(), b2.data(), gate.data(),
                 scratch.data());
    ks_->se_scale(c, x.data(), gate.data(), got.data(), 0, px);
    expect_near_all(got, want, 2e-5, "squeeze-excite");
  }
}

// The fast attention as the ATTENTION op runs it: K and V packed per head,
// then every (head, query chunk). false if the kernel refused the head width.
bool fast_attention(const KernelSet& ks, const AttentionShape& s, const std::vector<float>& q,
                    const std::vector<float>& k, const std::vector<float>& v, float scale,
                    std::vector<float>* out) {
  const int e = s.heads * s.head_dim, d = s.head_dim, lk = s.kv_len, lq = s.q_len;
  const int lk_pad = (lk + ks.attn_key_block - 1) / ks.attn_key_block * ks.attn_key_block;
  std::vector<float> kt(size_t(e) * lk_pad), vp(size_t(e) * lk_pad), scratch(ks.attn_scratch(d));
  bool supported = true;
  for (int h = 0; h < s.heads; ++h) {
    ks.attn_pack_kv(lk, lk_pad, d, k.data(), size_t(e), v.data(), size_t(e), h, kt.data(),
                    vp.data());
  }
  for (int h = 0; h < s.heads; ++h) {
    for (int q0 = 0; q0 < lq; q0 += ks.attn_max_rows) {
      const int rows = lq - q0 < ks.attn_max_rows ? lq - q0 : ks.attn_max_rows;
      supported &= ks.attn_block(rows, lk, d, q.data(), size_t(e), kt.data(), vp.data(), lk_pad,
                                 scale, out->data(), size_t(e), h, q0, scratch.data());
    }
  }
  return supported;
}

TEST_P(FastKernels, FusedAttention) {
  for (int round = 0; round < 40; ++round) {
    const int heads = pick(1, 8), d = round < 4 ? 32 : pick(1, 64), lq = pick(1, 40);
    const int lk = round % 5 == 0 ? pick(129, 400) : pick(1, 160);
    const int e = heads * d;
    const AttentionShape s{lq, lk, heads, d};
    const auto q = rnd(size_t(lq) * e, 2.0f), k = rnd(size_t(lk) * e, 2.0f),
               v = rnd(size_t(lk) * e);
    const float scale = 1.0f / std::sqrt(float(d));
    std::vector<float> want(size_t(lq) * e), got(want.size(), -3.0f),
        rs(f32_attention__ref_scratch(s));
    f32_attention__ref(s, q.data(), k.data(), v.data(), scale, want.data(), rs.data());
    const bool supported = fast_attention(*ks_, s, q, k, v, scale, &got);
    if (!supported) {
      EXPECT_GT(d, 8 * ks_->lanes) << "refused a head width it should handle";
      continue;
    }
    expect_near_all(got, want, 2e-5,
                    "attention d=" + std::to_string(d) + " lk=" + std::to_string(lk));
  }
}

// The kernel weighs key blocks against a fixed reference exponent (0 for a
// row's first block) and falls back to the block's maximum when that would
// overflow or lose the row: later key blocks scoring far above the first
// (~180 nats here), a first block far above the rest, and every score far
// below zero.
TEST_P(FastKernels, FusedAttentionScoreJumpsBetweenKeyBlocks) {
  for (int round = 0; round < 12; ++round) {
    const int heads = pick(1, 3), d = round < 4 ? 32 : pick(1, 40), lq = pick(1, 20);
    const int lk = pick(ks_->attn_key_block + 1, 3 * ks_->attn_key_block + 7);
    const int e = heads * d;
    const AttentionShape s{lq, lk, heads, d};
    auto q = rnd(size_t(lq) * e, 4.0f), k = rnd(size_t(lk) * e), v = rnd(size_t(lk) * e);
    const int kind = round % 3;  // 0 rising, 1 falling, 2 all far below zero
    for (int j = 0; j < lk; ++j) {
      const bool late = j >= ks_->attn_key_block;
      const float gain = kind == 0   ? (late ? 40.0f : 0.05f)
                         : kind == 1 ? (late ? 0.05f : 40.0f)
                                     : 40.0f;
      for (int c = 0; c < e; ++c) {
        float& kv = k[size_t(j) * e + c];
        kv = kind == 2 ? -std::fabs(kv) * gain : kv * gain;
      }
    }
    if (kind == 2) {
      for (float& x : q) x = std::fabs(x) + 0.5f;
    }
    const float scale = 1.0f / std::sqrt(float(d));
    std::vector<float> want(size_t(lq) * e), got(want.size(), -3.0f),
        rs(f32_attention__ref_scratch(s));
    f32_attention__ref(s, q.data(), k.data(), v.data(), scale, want.data(), rs.data());
    if (!fast_attention(*ks_, s, q, k, v, scale, &got)) continue;
    expect_near_all(got, want, 2e-5,
                    std::string(kind == 0   ? "rising"
                                : kind == 1 ? "falling"
                                            : "negative") +
                        " d=" + std::to_string(d) + " lk=" + std::to_string(lk));
  }
}

// A NaN in one query row (head 0) or one key row (head 1): the query's row
// of head 0 is NaN and every row of head 1 (each weighs the NaN key), as in
// the reference; the rest equals the reference's. The weights' clamp keeps a
// NaN score NaN on every ISA (kernels/simd/attention_impl.inl).
TEST_P(FastKernels, FusedAttentionKeepsNaNInTheRowsItReaches) {
  const AttentionShape s{11, 150, 2, 32};
  const int e = 64;
  auto q = rnd(size_t(11) * e, 2.0f), k = rnd(size_t(150) * e, 2.0f), v = rnd(size_t(150) * e);
  q[size_t(4) * e + 3] = std::numeric_limits<float>::quiet_NaN();         // query 4, head 0
  k[size_t(140) * e + 32 + 5] = std::numeric_limits<float>::quiet_NaN();  // key 140, head 1
  std::vector<float> want(q.size()), got(q.size(), -3.0f), rs(f32_attention__ref_scratch(s));
  f32_attention__ref(s, q.data(), k.data(), v.data(), 0.18f, want.data(), rs.data());
  ASSERT_TRUE(fast_attention(*ks_, s, q, k, v, 0.18f, &got));
  for (int i = 0; i < 11; ++i) {
    for (int c = 0; c < e; ++c) {
      const size_t at = size_t(i) * e + c;
      const bool poisoned = c >= 32 || i == 4;
      ASSERT_EQ(std::isnan(want[at]), poisoned) << "reference row " << i << " col " << c;
      if (poisoned) {
        EXPECT_TRUE(std::isnan(got[at])) << "row " << i << " col " << c;
      } else {
        ASSERT_NEAR(got[at], want[at], 2e-5 * (1.0 + std::fabs(want[at]))) << i << " " << c;
      }
    }
  }
}

// Single-query attention scores: odd widths (partial vectors and chunks),
// head counts around the kernel's group of eight, with and without
// positions, a row range inside a padded score matrix.
TEST_P(FastKernels, CrossAttentionScores) {
  for (int round = 0; round < 30; ++round) {
    const int heads = pick(1, 19), e = round < 3 ? 256 : pick(1, 300), rows = pick(1, 50);
    const int j0 = pick(0, rows - 1), j1 = pick(j0 + 1, rows);
    const size_t ls = size_t(rows) + pick(0, 3);
    const bool with_pos = round % 3 != 0;
    const auto m = rnd(size_t(rows) * e), p = rnd(size_t(rows) * e), qt = rnd(size_t(heads) * e);
    std::vector<float> want(size_t(heads) * ls, -7.0f), got(want);
    f32_cross_scores__ref(e, heads, m.data(), with_pos ? p.data() : nullptr, qt.data(), want.data(),
                          ls, j0, j1);
    ks_->cross_scores(e, heads, m.data(), with_pos ? p.data() : nullptr, qt.data(), got.data(), ls,
                      j0, j1);
    expect_near_all(got, want, 2e-5 * std::sqrt(float(e)),
                    "cross scores e=" + std::to_string(e) + " heads=" + std::to_string(heads));
  }
}

// Camera frame -> network input: every pixel format, odd frame and output
// sizes (down- and upscaling, one output pixel, a partial vector), one and
// three channels, padded strides, random normalisation.
TEST_P(FastKernels, PreprocessEveryFormat) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> mean(0.2f, 0.6f), std_(0.1f, 0.5f);
  const PixelFormat formats[] = {PixelFormat::kRgb24, PixelFormat::kBgr24, PixelFormat::kYuyv,
                                 PixelFormat::kUyvy,  PixelFormat::kNv12,  PixelFormat::kGray8};
  struct Geometry {
    int w, h, size, channels;
  };
  const Geometry geometries[] = {{37, 29, 17, 3},  {29, 37, 5, 3}, {640, 480, 64, 3},
                                 {101, 67, 33, 1}, {3, 3, 1, 3},   {131, 75, 224, 3},
                                 {64, 64, 64, 3},  {1, 1, 7, 3},   {250, 130, 129, 1}};
  auto plan = std::make_unique<PreprocessPlan>();
  for (PixelFormat f : formats) {
    for (const Geometry& g : geometries) {
      size_t stride = min_stride(f, g.w) + rng() % 7;
      if (f == PixelFormat::kNv12) stride = std::max(stride, size_t((g.w + 1) / 2) * 2);
      std::vector<uint8_t> frame(stride * size_t(g.h + (g.h + 1) / 2) + 16);
      for (uint8_t& b : frame) b = uint8_t(rng());
      PreprocessParams p{
          g.size, g.channels, {mean(rng), mean(rng), mean(rng)}, {std_(rng), std_(rng), std_(rng)}};
      const ImageView img{frame.data(), f, g.w, g.h, stride};
      const size_t n = size_t(g.size) * g.size * g.channels;
      std::vector<float> got(n + 8, -7.0f), want(n);
      ASSERT_TRUE(plan_preprocess(p, f, g.w, g.h, plan.get(), ks_->preprocess));
      preprocess_image(*plan, img, got.data());
      preprocess_image__ref(img, p, want.data());
      const std::string where = std::string(pixel_format_name(f)) + " " + std::to_string(g.w) +
                                "x" + std::to_string(g.h) + " -> " + std::to_string(g.size) + " c" +
                                std::to_string(g.channels);
      for (size_t i = 0; i < n; ++i) {
        ASSERT_NEAR(got[i], want[i], 1e-5f * std::max(1.0f, std::fabs(want[i])))
            << where << " at " << i;
      }
      for (size_t i = n; i < n + 8; ++i)
        ASSERT_EQ(got[i], -7.0f) << where << ": wrote past the end";
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Isa, FastKernels, ::testing::ValuesIn(kIsas),
                         [](const auto& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace aprt::kernels
