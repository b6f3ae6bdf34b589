// fp32 attention: the references against the full score matrix and the
// project-then-attend formula; every ISA's fused kernel and cross-attention
// scores against the references on random odd shapes, score jumps between
// key blocks and NaN rows.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "kernels/attention/f32_attention__ref.h"
#include "kernels/attention/f32_cross_attention_1q__ref.h"
#include "kernels/gemm/f32_gemm__ref.h"
#include "tests/kernels/kernel_test_support.h"

namespace aprt::kernels {
namespace {

using namespace aprt::kernels::testing;

class AttentionKernels : public F32KernelTest {};

TEST(AttentionRef, AttentionMatchesFullScoreMatrix) {
  std::mt19937 g(5);
  for (int round = 0; round < 30; ++round) {
    const AttentionShape s{1 + int(g() % 17), 1 + int(g() % 29), 1 + int(g() % 4),
                           1 + int(g() % 9)};
    const int e = s.heads * s.head_dim;
    const auto q = rnd(size_t(s.q_len) * e, g, 2.0f), k = rnd(size_t(s.kv_len) * e, g, 2.0f),
               v = rnd(size_t(s.kv_len) * e, g);
    const float scale = 1.0f / std::sqrt(float(s.head_dim));
    std::vector<float> o(size_t(s.q_len) * e), scratch(f32_attention__ref_scratch(s));
    f32_attention__ref(s, q.data(), k.data(), v.data(), scale, o.data(), scratch.data());
    std::vector<double> want(o.size(), 0.0);
    for (int h = 0; h < s.heads; ++h) {
      std::vector<double> sc(size_t(s.q_len) * s.kv_len);
      for (int i = 0; i < s.q_len; ++i) {
        double mx = -1e300, sum = 0;
        for (int j = 0; j < s.kv_len; ++j) {
          double d = 0;
          for (int t = 0; t < s.head_dim; ++t)
            d += double(q[i * e + h * s.head_dim + t]) * k[j * e + h * s.head_dim + t];
          sc[i * s.kv_len + j] = d * scale;
          mx = std::max(mx, sc[i * s.kv_len + j]);
        }
        for (int j = 0; j < s.kv_len; ++j)
          sum += (sc[i * s.kv_len + j] = std::exp(sc[i * s.kv_len + j] - mx));
        for (int j = 0; j < s.kv_len; ++j)
          for (int t = 0; t < s.head_dim; ++t)
            want[i * e + h * s.head_dim + t] +=
                sc[i * s.kv_len + j] / sum * v[j * e + h * s.head_dim + t];
      }
    }
    expect_close(o, want, 1e-5);
  }
}

// The single-query algebra against the plain path: project the memory to keys
// and values, then attend.
TEST(AttentionRef, CrossAttentionOneQueryEqualsProjectThenAttend) {
  std::mt19937 g(8);
  for (int round = 0; round < 20; ++round) {
    const int heads = 1 + int(g() % 4), d = 1 + int(g() % 9), l = 1 + int(g() % 50);
    const int e = heads * d;
    const bool with_pos = g() % 2;
    const auto q = rnd(size_t(e), g), m = rnd(size_t(l) * e, g), pos = rnd(size_t(l) * e, g);
    const auto wk = rnd(size_t(e) * e, g), bk = rnd(size_t(e), g), wv = rnd(size_t(e) * e, g),
               bv = rnd(size_t(e), g);
    std::vector<float> keys_in(m);
    if (with_pos) {
      for (size_t i = 0; i < keys_in.size(); ++i) keys_in[i] += pos[i];
    }
    std::vector<float> k(size_t(l) * e), v(size_t(l) * e), plain(static_cast<size_t>(e)),
        fused(static_cast<size_t>(e));
    f32_gemm__ref({l, e, e}, keys_in.data(), wk.data(), bk.data(), nullptr, Act::kNone, k.data());
    f32_gemm__ref({l, e, e}, m.data(), wv.data(), bv.data(), nullptr, Act::kNone, v.data());
    const float scale = 1.0f / std::sqrt(float(d));
    const AttentionShape s{1, l, heads, d};
    std::vector<float> scratch(f32_attention__ref_scratch(s));
    f32_attention__ref(s, q.data(), k.data(), v.data(), scale, plain.data(), scratch.data());
    std::vector<float> scratch2(f32_cross_attention_1q__ref_scratch(l, e));
    f32_cross_attention_1q__ref(l, heads, e, q.data(), m.data(), with_pos ? pos.data() : nullptr,
                                wk.data(), wv.data(), bv.data(), scale, fused.data(),
                                scratch2.data());
    for (int i = 0; i < e; ++i) EXPECT_NEAR(fused[i], plain[i], 2e-5 * (1 + std::fabs(plain[i])));
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

TEST_P(AttentionKernels, FusedAttention) {
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
TEST_P(AttentionKernels, FusedAttentionScoreJumpsBetweenKeyBlocks) {
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
// NaN score NaN on every ISA (kernels/attention/f32_attention_impl.inl).
TEST_P(AttentionKernels, FusedAttentionKeepsNaNInTheRowsItReaches) {
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
TEST_P(AttentionKernels, CrossAttentionScores) {
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

INSTANTIATE_TEST_SUITE_P(Isa, AttentionKernels, ::testing::ValuesIn(f32_cases()),
                         case_name<F32Case>);

}  // namespace
}  // namespace aprt::kernels
