// The int8 kernels (kernels/common/qkernel_set.h) against their reference,
// bit for bit, on random odd shapes, for every ISA this CPU can run (the
// others are skipped, and say so): GEMM with every epilogue, called whole and
// in row/panel pieces as the thread pool splits it, and the quantiser on
// halfway values, huge values, infinities and NaN; the depthwise convolution
// on odd channel counts, kernel sizes, strides and asymmetric padding. The
// int8-score attention (where a table has one) against the fp32 reference
// over fake-quantised Q and K, to the fp32 softmax's tolerance.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "kernels/common/cpu_features.h"
#include "kernels/common/qkernel_set.h"
#include "kernels/common/qs8_attention.h"
#include "kernels/ref/f32_attention__ref.h"
#include "kernels/ref/qs8_attention__ref.h"
#include "kernels/ref/qs8_dwconv2d__ref.h"
#include "kernels/ref/qs8_gemm__ref.h"

namespace aprt::kernels {
namespace {

struct QIsa {
  const char* name;
  const QKernelSet* (*get)();
  bool (*supported)();
};

const QIsa kQIsas[] = {
    {"avx512vnni", qkernel_set_avx512vnni, [] { return cpu_features().avx512_vnni; }},
    {"avx2", qkernel_set_avx2, [] { return cpu_features().avx2_fma; }},
    {"neondot", qkernel_set_neondot, [] { return cpu_features().neon_dot; }},
    {"neon", qkernel_set_neon, [] { return cpu_features().neon; }},
};

class QKernels : public ::testing::TestWithParam<QIsa> {
 protected:
  void SetUp() override {
    ks_ = GetParam().get();
    if (!ks_) GTEST_SKIP() << GetParam().name << " is not part of this build";
    if (!GetParam().supported()) GTEST_SKIP() << "this CPU cannot run " << GetParam().name;
  }
  const QKernelSet* ks_ = nullptr;
};

TEST_P(QKernels, GemmBitExactOnOddShapes) {
  std::mt19937 rng(1234);
  struct Shape {
    int m, n, k;
  };
  const Shape shapes[] = {{1, 1, 1},     {3, 5, 2},      {7, 33, 3},     {9, 17, 5},
                          {13, 64, 64},  {8, 32, 4},     {17, 70, 257},  {6, 16, 31},
                          {37, 48, 129}, {2, 100, 768},  {25, 31, 9},    {4, 96, 1},
                          {11, 129, 33}, {1024, 96, 16}, {256, 24, 144}, {1024, 16, 32}};
  std::uniform_real_distribution<float> mu(1e-4f, 3e-2f), bi(-2.0f, 2.0f);
  for (const Shape& s : shapes) {
    for (int variant = 0; variant < 4; ++variant) {
      const bool with_bias = variant & 1, with_residual = variant & 2;
      const size_t lda = size_t(s.k) + rng() % 5;  // padded rows
      std::vector<uint8_t> a(size_t(s.m) * lda);
      for (uint8_t& v : a) v = uint8_t(rng());
      std::vector<int8_t> w(size_t(s.n) * s.k);
      for (int8_t& v : w) v = int8_t(int(rng() % 255) - 127);  // symmetric: [-127, 127]
      std::vector<float> mult(s.n), bias(s.n), residual(size_t(s.m) * (s.n + 3));
      for (float& v : mult) v = mu(rng);
      for (float& v : bias) v = bi(rng);
      for (float& v : residual) v = bi(rng);
      const int32_t a_zero = int32_t(rng() % 256);
      std::vector<int32_t> colsum(s.n);
      qs8_column_sums(s.n, s.k, w.data(), colsum.data());
      std::vector<int8_t> packed(qs8_pack_w_bytes(s.n, s.k, ks_->nr, ks_->kgroup));
      qs8_pack_w(s.n, s.k, ks_->nr, ks_->kgroup, w.data(), packed.data());
      for (Act act : {Act::kNone, Act::kRelu}) {
        const size_t ldc = size_t(s.n) + 2;
        std::vector<float> want(size_t(s.m) * ldc, 0.0f), got(size_t(s.m) * ldc + 16, 0.0f);
        qu8s8_gemm__ref(s.m, s.n, s.k, a.data(), lda, a_zero, w.data(), mult.data(),
                        with_bias ? bias.data() : nullptr,
                        with_residual ? residual.data() : nullptr, size_t(s.n) + 3, act,
                        want.data(), ldc);
        QGemmArgs g{s.m,
                    s.n,
                    s.k,
                    a.data(),
                    lda,
                    a_zero,
                    packed.data(),
                    colsum.data(),
                    mult.data(),
                    with_bias ? bias.data() : nullptr,
                    with_residual ? residual.data() : nullptr,
                    size_t(s.n) + 3,
                    got.data(),
                    ldc,
                    act};
        const int panels = (s.n + ks_->nr - 1) / ks_->nr;
        // Whole, then split the way the thread pool splits: rows and panels in pieces.
        for (int split = 0; split < 2; ++split) {
          std::fill(got.begin(), got.end(), 0.0f);
          if (split == 0) {
            ks_->gemm(g, 0, s.m, 0, panels);
          } else {
            const int rm = s.m / 2, pm = panels / 2;
            ks_->gemm(g, 0, rm, 0, pm);
            ks_->gemm(g, rm, s.m, 0, pm);
            ks_->gemm(g, 0, rm, pm, panels);
            ks_->gemm(g, rm, s.m, pm, panels);
          }
          for (int i = 0; i < s.m; ++i) {
            for (int j = 0; j < s.n; ++j) {
              const float x = got[size_t(i) * ldc + j], y = want[size_t(i) * ldc + j];
              ASSERT_EQ(std::memcmp(&x, &y, sizeof x), 0)
                  << ks_->isa << " " << s.m << "x" << s.n << "x" << s.k << " variant " << variant
                  << " act " << int(act) << " split " << split << " at " << i << "," << j << ": "
                  << x << " vs " << y;
            }
            // Columns past n in the padded row are not written.
            for (size_t j = size_t(s.n); j < ldc; ++j) ASSERT_EQ(got[size_t(i) * ldc + j], 0.0f);
          }
        }
      }
    }
  }
}

TEST_P(QKernels, QuantizeBitExact) {
  std::mt19937 rng(99);
  std::normal_distribution<float> d(0.0f, 3.0f);
  for (size_t n :
       {size_t(1), size_t(7), size_t(8), size_t(15), size_t(16), size_t(33), size_t(1000)}) {
    std::vector<float> x(n);
    for (float& v : x) v = d(rng);
    // Halfway cases, the clamps, and values the conversion cannot hold.
    const float special[] = {0.5f,
                             1.5f,
                             2.5f,
                             -0.5f,
                             -1.5f,
                             1e9f,
                             -1e9f,
                             std::numeric_limits<float>::infinity(),
                             -std::numeric_limits<float>::infinity(),
                             std::numeric_limits<float>::quiet_NaN(),
                             127.5f,
                             -128.5f};
    for (size_t i = 0; i < n && i < sizeof special / sizeof special[0]; ++i)
      x[i * 7 % n] = special[i];
    for (float inv : {1.0f, 12.7f, 0.25f}) {
      for (int32_t zero : {0, 128, 255, 37}) {
        std::vector<uint8_t> want(n), got(n + 8, 0xEE);
        f32_qu8_quantize__ref(n, x.data(), inv, zero, want.data());
        ks_->quantize(n, x.data(), inv, zero, got.data());
        for (size_t i = 0; i < n; ++i) {
          ASSERT_EQ(got[i], want[i]) << ks_->isa << " n " << n << " x " << x[i] << " inv " << inv
                                     << " zero " << zero << " at " << i;
        }
        for (size_t i = n; i < n + 8; ++i) ASSERT_EQ(got[i], 0xEE) << "wrote past the end";
      }
    }
  }
}

TEST_P(QKernels, DwConvBitExactOnOddShapes) {
  std::mt19937 rng(4321);
  struct Case {
    int h, w, c, k, stride, pt, pl, pb, pr;
  };
  const Case cases[] = {{1, 1, 1, 3, 1, 1, 1, 1, 1},   {5, 7, 3, 3, 1, 1, 1, 1, 1},
                        {9, 8, 17, 3, 2, 0, 0, 1, 1},  {6, 11, 33, 5, 1, 2, 2, 2, 2},
                        {13, 9, 16, 5, 2, 1, 2, 2, 1}, {4, 4, 40, 3, 2, 1, 0, 1, 0},
                        {8, 5, 7, 1, 1, 0, 0, 0, 0},   {16, 16, 96, 3, 2, 0, 0, 1, 1},
                        {3, 17, 65, 5, 1, 0, 4, 4, 0}, {32, 32, 32, 3, 1, 1, 1, 1, 1},
                        {4, 4, 480, 3, 1, 1, 1, 1, 1}, {8, 8, 240, 5, 1, 2, 2, 2, 2}};
  std::uniform_real_distribution<float> mu(1e-4f, 3e-2f), bi(-2.0f, 2.0f);
  for (const Case& cs : cases) {
    Conv2dShape s{cs.h, cs.w, cs.c, 0, 0, cs.c, cs.k, cs.k, cs.stride, cs.stride, cs.pt, cs.pl};
    s.out_h = (cs.h + cs.pt + cs.pb - cs.k) / cs.stride + 1;
    s.out_w = (cs.w + cs.pl + cs.pr - cs.k) / cs.stride + 1;
    std::vector<uint8_t> x(size_t(cs.h) * cs.w * cs.c);
    for (uint8_t& v : x) v = uint8_t(rng());
    std::vector<int8_t> w(size_t(cs.k) * cs.k * cs.c);
    for (int8_t& v : w) v = int8_t(int(rng() % 255) - 127);
    std::vector<float> wf(w.begin(), w.end()), mult(cs.c), bias(cs.c);
    for (float& v : mult) v = mu(rng);
    for (float& v : bias) v = bi(rng);
    const int32_t zero = int32_t(rng() % 256);
    const size_t out = size_t(s.out_h) * s.out_w * cs.c;
    for (Act act : {Act::kNone, Act::kRelu, Act::kSilu}) {
      std::vector<float> want(out), got(out + 16, -7.0f);
      qu8s8_dwconv2d__ref(s, x.data(), zero, w.data(), mult.data(), bias.data(), act, want.data());
      const QDwConvArgs a{s, x.data(), zero, wf.data(), mult.data(), bias.data(), act, got.data()};
      // In row pieces, as the thread pool splits it.
      if (act == Act::kNone) {  // whole, as one task runs it
        ks_->dwconv_rows(a, 0, s.out_h);
      } else {  // in row pieces, as the thread pool splits it
        for (int r0 = 0; r0 < s.out_h; r0 += 2) ks_->dwconv_rows(a, r0, std::min(r0 + 2, s.out_h));
      }
      for (size_t i = 0; i < out; ++i) {
        if (act == Act::kSilu) {  // the vector sigmoid is an approximation
          ASSERT_NEAR(got[i], want[i], 1e-5f * (1.0f + std::fabs(want[i]))) << i;
        } else {
          ASSERT_EQ(got[i], want[i]) << "case " << cs.h << "x" << cs.w << "x" << cs.c << " k"
                                     << cs.k << " s" << cs.stride << " at " << i;
        }
      }
      for (size_t i = out; i < got.size(); ++i) ASSERT_EQ(got[i], -7.0f) << "wrote past the end";
    }
  }
}

// Runs the table's int8-score attention over every head and query chunk as
// the op does; false if the table has none or refuses the shape.
bool q8_attention(const QKernelSet& qs, const AttentionShape& s, const std::vector<float>& q,
                  const std::vector<float>& k, const std::vector<float>& v, float scale,
                  std::vector<float>* out) {
  if (!qs.attn_block) return false;
  const int e = s.heads * s.head_dim, d = s.head_dim;
  const int lk_pad = (s.kv_len + qs.attn_key_block - 1) / qs.attn_key_block * qs.attn_key_block;
  std::vector<uint8_t> kq(qs.attn_kq_bytes(s.heads, lk_pad, d));
  std::vector<float> vp(size_t(e) * lk_pad), scratch(qs.attn_scratch(d));
  for (int h = 0; h < s.heads; ++h) {
    qs.attn_pack_kv(s.kv_len, lk_pad, d, k.data(), size_t(e), v.data(), size_t(e), h, kq.data(),
                    vp.data());
  }
  bool ok = true;
  for (int h = 0; h < s.heads; ++h) {
    for (int q0 = 0; q0 < s.q_len; q0 += qs.attn_max_rows) {
      const int rows = std::min(qs.attn_max_rows, s.q_len - q0);
      ok &= qs.attn_block(rows, s.kv_len, d, q.data(), size_t(e), kq.data(), vp.data(), lk_pad,
                          scale, out->data(), size_t(e), h, q0, scratch.data());
    }
  }
  return ok;
}

TEST(QAttention, QuantisationRoundsToNearestEvenWithinTheRowScale) {
  const float x[5] = {-3.0f, 1.5f, 0.0f, 3.0f, 0.75f};
  float inv = 0.0f;
  const float scale = qs8_row_scale(x, 5, &inv);
  EXPECT_FLOAT_EQ(scale, 3.0f / 127.0f);
  EXPECT_EQ(qs8_round(x[0], inv), -127);
  EXPECT_EQ(qs8_round(x[3], inv), 127);
  EXPECT_EQ(qs8_round(x[1], inv), 64);  // 63.5: ties to even
  const float zero[3] = {0.0f, 0.0f, 0.0f};
  EXPECT_EQ(qs8_row_scale(zero, 3, &inv), 0.0f);
  EXPECT_EQ(qs8_round(0.0f, inv), 0);
  std::vector<float> y(5);
  qs8_fake_quantize_rows(1, 1, 5, x, 5, y.data());
  EXPECT_FLOAT_EQ(y[3], 3.0f);
  EXPECT_FLOAT_EQ(y[1], 64.0f * scale);
  // A NaN or an infinity anywhere in the row: the scale, and so every value
  // of the row, is NaN or infinite -- garbage stays visible, never plausible.
  const float bad[3] = {1.0f, std::numeric_limits<float>::quiet_NaN(), 2.0f};
  EXPECT_TRUE(std::isnan(qs8_row_scale(bad, 3, &inv)));
  EXPECT_EQ(qs8_round(std::numeric_limits<float>::quiet_NaN(), 1.0f), 0);
  qs8_fake_quantize_rows(1, 1, 3, bad, 3, y.data());
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(std::isnan(y[i])) << i;
  const float big[2] = {1.0f, std::numeric_limits<float>::infinity()};
  qs8_fake_quantize_rows(1, 1, 2, big, 2, y.data());
  for (int i = 0; i < 2; ++i) EXPECT_FALSE(std::isfinite(y[i])) << i;
}

// Q, K and V uniform in [-1, 1] for shape s, seeded.
struct Qkv {
  std::vector<float> q, k, v;
};
Qkv random_qkv(const AttentionShape& s, unsigned seed) {
  const size_t e = size_t(s.heads) * s.head_dim;
  Qkv t{std::vector<float>(size_t(s.q_len) * e), std::vector<float>(size_t(s.kv_len) * e),
        std::vector<float>(size_t(s.kv_len) * e)};
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (auto* m : {&t.q, &t.k, &t.v}) {
    for (float& x : *m) x = u(rng);
  }
  return t;
}

// A NaN in one query row: that row's output (of its head) is NaN, as the
// reference's -- the weights' clamp keeps a NaN score NaN -- and the other
// rows' outputs are untouched (equal to the reference's) and finite.
TEST_P(QKernels, AttentionScoresInt8NaNRowStaysInItsRow) {
  if (!ks_->attn_block) GTEST_SKIP() << GetParam().name << " has no int8-score attention";
  const AttentionShape s{9, 40, 2, 32};
  const int e = 64;
  auto [q, k, v] = random_qkv(s, 3);
  q[size_t(4) * e + 3] = std::numeric_limits<float>::quiet_NaN();  // row 4, head 0
  std::vector<float> got(q.size(), -3.0f), want(q.size()), rs(qs8_attention__ref_scratch(s));
  qs8_attention__ref(s, q.data(), k.data(), v.data(), 0.18f, want.data(), rs.data());
  ASSERT_TRUE(q8_attention(*ks_, s, q, k, v, 0.18f, &got));
  for (int i = 0; i < 9; ++i) {
    for (int c = 0; c < e; ++c) {
      const size_t at = size_t(i) * e + c;
      if (i == 4 && c < 32) {
        EXPECT_TRUE(std::isnan(want[at])) << "reference row 4 col " << c;
        EXPECT_TRUE(std::isnan(got[at])) << "row 4 col " << c;
        continue;
      }
      ASSERT_TRUE(std::isfinite(got[at])) << "row " << i << " col " << c;
      ASSERT_NEAR(got[at], want[at], 2e-5 * (1.0 + std::fabs(want[at]))) << i << " " << c;
    }
  }
}

// A NaN in one key row and an infinity in another (the fuzzer's finding: a
// corrupt weight): the keys' heads come out NaN wherever the reference's do,
// the other head equals the reference's, and quantising the bad rows is
// defined behaviour (UBSan in the default run watches the correction term).
TEST_P(QKernels, AttentionScoresInt8NonFiniteKeyRows) {
  if (!ks_->attn_block) GTEST_SKIP() << GetParam().name << " has no int8-score attention";
  const AttentionShape s{7, 45, 3, 32};
  const int e = 96;
  auto [q, k, v] = random_qkv(s, 8);
  for (int c = 0; c < 32; ++c) k[size_t(6) * e + c] = std::numeric_limits<float>::quiet_NaN();
  k[size_t(30) * e + 64 + 5] = std::numeric_limits<float>::infinity();  // head 2
  std::vector<float> got(q.size(), -3.0f), want(q.size()), rs(qs8_attention__ref_scratch(s));
  qs8_attention__ref(s, q.data(), k.data(), v.data(), 0.18f, want.data(), rs.data());
  ASSERT_TRUE(q8_attention(*ks_, s, q, k, v, 0.18f, &got));
  int bad = 0;
  for (size_t at = 0; at < got.size(); ++at) {
    const int head = int(at % size_t(e)) / 32;
    if (head != 1) {
      EXPECT_EQ(std::isfinite(got[at]), std::isfinite(want[at])) << "at " << at;
      bad += !std::isfinite(want[at]);
      continue;
    }
    ASSERT_TRUE(std::isfinite(got[at])) << "at " << at;
    ASSERT_NEAR(got[at], want[at], 2e-5 * (1.0 + std::fabs(want[at]))) << "at " << at;
  }
  EXPECT_GT(bad, 0) << "the bad keys should reach their heads' outputs";
}

TEST_P(QKernels, AttentionScoresInt8OnOddShapes) {
  if (!ks_->attn_block) GTEST_SKIP() << GetParam().name << " has no int8-score attention";
  std::mt19937 rng(99);
  auto pick = [&](int lo, int hi) { return int(rng() % unsigned(hi - lo + 1)) + lo; };
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  int ran = 0;
  for (int round = 0; round < 40; ++round) {
    const int heads = pick(1, 8), d = round < 6 ? 32 : 4 * pick(1, 16), lq = pick(1, 300);
    const int lk = round % 4 == 0 ? pick(129, 420) : pick(1, 160);
    const int e = heads * d;
    const AttentionShape s{lq, lk, heads, d};
    // Scores of a few nats (gain 3) and, every third round, tens of nats
    // across key blocks (gain 30): the lazy rescaling's fallback runs too.
    const float gain = round % 3 == 2 ? 30.0f : 3.0f;
    std::vector<float> q(size_t(lq) * e), k(size_t(lk) * e), v(size_t(lk) * e);
    for (float& x : q) x = u(rng) * gain;
    for (float& x : k) x = u(rng);
    for (float& x : v) x = u(rng);
    const float scale = 1.0f / std::sqrt(float(d));
    std::vector<float> want(size_t(lq) * e), got(want.size(), -3.0f),
        rs(qs8_attention__ref_scratch(s));
    qs8_attention__ref(s, q.data(), k.data(), v.data(), scale, want.data(), rs.data());
    ASSERT_TRUE(q8_attention(*ks_, s, q, k, v, scale, &got)) << "d=" << d;
    ++ran;
    for (size_t i = 0; i < got.size(); ++i) {
      ASSERT_NEAR(got[i], want[i], 2e-5 * (1.0 + std::fabs(want[i])))
          << "d=" << d << " lq=" << lq << " lk=" << lk << " heads=" << heads << " at " << i;
    }
  }
  EXPECT_EQ(ran, 40);
}

// What the int8 scores cost against fp32 ones on the same data: a bound that
// catches a broken quantisation (a wrong scale or rounding moves outputs by
// far more), not an accuracy claim (docs/int8.md measures the pose).
TEST(QAttention, ReferenceStaysCloseToFp32Attention) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  const AttentionShape s{50, 200, 4, 32};
  const int e = 128;
  std::vector<float> q(size_t(50) * e), k(size_t(200) * e), v(size_t(200) * e);
  for (float& x : q) x = 3.0f * u(rng);
  for (float& x : k) x = u(rng);
  for (float& x : v) x = u(rng);
  std::vector<float> a(q.size()), b(q.size()), r1(f32_attention__ref_scratch(s)),
      r2(qs8_attention__ref_scratch(s));
  f32_attention__ref(s, q.data(), k.data(), v.data(), 0.177f, a.data(), r1.data());
  qs8_attention__ref(s, q.data(), k.data(), v.data(), 0.177f, b.data(), r2.data());
  double worst = 0.0;
  for (size_t i = 0; i < a.size(); ++i) worst = std::max(worst, double(std::fabs(a[i] - b[i])));
  EXPECT_LT(worst, 0.02);
  EXPECT_GT(worst, 0.0);  // it did quantise
}

INSTANTIATE_TEST_SUITE_P(Isa, QKernels, ::testing::ValuesIn(kQIsas),
                         [](const ::testing::TestParamInfo<QIsa>& i) { return i.param.name; });

TEST(QKernelSet, BestIsOneThisCpuRuns) {
  const QKernelSet* best = qkernel_set_best();
  const CpuFeatures& f = cpu_features();
  if (f.avx512_vnni) {
    ASSERT_NE(best, nullptr);
    EXPECT_STREQ(best->isa, "avx512vnni");
  } else if (f.avx2_fma) {
    ASSERT_NE(best, nullptr);
    EXPECT_STREQ(best->isa, "avx2");
  } else if (f.neon) {
    ASSERT_NE(best, nullptr);
    EXPECT_STREQ(best->isa, f.neon_dot ? "neondot" : "neon");
  }
}

}  // namespace
}  // namespace aprt::kernels
