// Attention with int8 scores: the row quantisation by hand, the reference
// against fp32 attention, every int8 part's kernel (where it has one)
// against the fp32 reference over fake-quantised Q and K, NaN and infinite rows.
#include "kernels/attention/qs8_attention.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "kernels/attention/f32_attention__ref.h"
#include "kernels/attention/qs8_attention__ref.h"
#include "tests/kernels/kernel_test_support.h"

namespace aprt::kernels {
namespace {

using namespace aprt::kernels::testing;

class QAttentionKernels : public Qs8KernelTest {};

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
TEST_P(QAttentionKernels, AttentionScoresInt8NaNRowStaysInItsRow) {
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
TEST_P(QAttentionKernels, AttentionScoresInt8NonFiniteKeyRows) {
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

TEST_P(QAttentionKernels, AttentionScoresInt8OnOddShapes) {
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

INSTANTIATE_TEST_SUITE_P(Isa, QAttentionKernels, ::testing::ValuesIn(qs8_cases()),
                         case_name<Qs8Case>);

}  // namespace
}  // namespace aprt::kernels
