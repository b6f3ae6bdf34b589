// The reference kernels against independent double-precision formulas on
// random odd shapes. (The fast kernels are then tested against these.)
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "kernels/ref/f32_attention__ref.h"
#include "kernels/ref/f32_conv2d__ref.h"
#include "kernels/ref/f32_cross_attention_1q__ref.h"
#include "kernels/ref/f32_dwconv2d__ref.h"
#include "kernels/ref/f32_elementwise__ref.h"
#include "kernels/ref/f32_layernorm__ref.h"
#include "kernels/ref/f32_linear__ref.h"
#include "kernels/ref/f32_squeeze_excite__ref.h"

namespace aprt::kernels {
namespace {

std::vector<float> rnd(size_t n, std::mt19937& g, float s = 1.0f) {
  std::uniform_real_distribution<float> u(-s, s);
  std::vector<float> v(n);
  for (auto& x : v) x = u(g);
  return v;
}

double act_d(double x, Act a) {
  switch (a) {
    case Act::kNone: return x;
    case Act::kSilu: return x / (1 + std::exp(-x));
    case Act::kGelu: return 0.5 * x * (1 + std::erf(x / std::sqrt(2.0)));
    case Act::kSigmoid: return 1 / (1 + std::exp(-x));
    case Act::kRelu: return x > 0 ? x : 0;
  }
  return x;
}

void expect_close(const std::vector<float>& got, const std::vector<double>& want, double tol) {
  ASSERT_EQ(got.size(), want.size());
  for (size_t i = 0; i < got.size(); ++i) {
    ASSERT_NEAR(got[i], want[i], tol * (1 + std::fabs(want[i]))) << "at " << i;
  }
}

// Output size under explicit (t, l) padding and total padding (pt+pb, pl+pr).
Conv2dShape conv_shape(int h, int w, int ci, int co, int kh, int kw, int s, int pt, int pl, int pb,
                       int pr) {
  return {h, w,  ci, (h + pt + pb - kh) / s + 1, (w + pl + pr - kw) / s + 1, co, kh, kw, s,
          s, pt, pl};
}

TEST(RefKernels, Conv2dMatchesDirectFormula) {
  std::mt19937 g(1);
  for (int round = 0; round < 40; ++round) {
    const int h = 1 + int(g() % 9), w = 1 + int(g() % 9), ci = 1 + int(g() % 7),
              co = 1 + int(g() % 9);
    const int k = (g() % 2) ? 3 : (g() % 2 ? 1 : 5), s = 1 + int(g() % 2);
    const int pt = int(g() % k), pl = int(g() % k), pb = int(g() % k), pr = int(g() % k);
    if (h + pt + pb < k || w + pl + pr < k) continue;
    const Conv2dShape sh = conv_shape(h, w, ci, co, k, k, s, pt, pl, pb, pr);
    const auto x = rnd(size_t(h) * w * ci, g), wt = rnd(size_t(co) * k * k * ci, g),
               b = rnd(size_t(co), g);
    const auto res = rnd(size_t(sh.out_h) * sh.out_w * co, g);
    const Act act = Act(g() % 5);
    std::vector<float> y(res.size());
    f32_conv2d__ref(sh, x.data(), wt.data(), b.data(), res.data(), act, y.data());
    std::vector<double> want(y.size());
    for (int oy = 0; oy < sh.out_h; ++oy)
      for (int ox = 0; ox < sh.out_w; ++ox)
        for (int c = 0; c < co; ++c) {
          double acc = b[c];
          for (int ky = 0; ky < k; ++ky)
            for (int kx = 0; kx < k; ++kx)
              for (int i = 0; i < ci; ++i) {
                const int iy = oy * s + ky - pt, ix = ox * s + kx - pl;
                if (iy < 0 || ix < 0 || iy >= h || ix >= w) continue;
                acc += double(x[(iy * w + ix) * ci + i]) * wt[((c * k + ky) * k + kx) * ci + i];
              }
          const size_t o = (size_t(oy) * sh.out_w + ox) * co + c;
          want[o] = act_d(acc, act) + res[o];
        }
    expect_close(y, want, 1e-5);
  }
}

TEST(RefKernels, DepthwiseMatchesDirectFormula) {
  std::mt19937 g(2);
  for (int round = 0; round < 40; ++round) {
    const int h = 1 + int(g() % 11), w = 1 + int(g() % 11), c = 1 + int(g() % 19);
    const int k = (g() % 2) ? 3 : 5, s = 1 + int(g() % 2);
    const int pt = int(g() % k), pl = int(g() % k), pb = int(g() % k), pr = int(g() % k);
    if (h + pt + pb < k || w + pl + pr < k) continue;
    const Conv2dShape sh = conv_shape(h, w, c, c, k, k, s, pt, pl, pb, pr);
    const auto x = rnd(size_t(h) * w * c, g), wt = rnd(size_t(k) * k * c, g), b = rnd(size_t(c), g);
    const Act act = Act(g() % 5);
    std::vector<float> y(size_t(sh.out_h) * sh.out_w * c);
    f32_dwconv2d__ref(sh, x.data(), wt.data(), b.data(), act, y.data());
    std::vector<double> want(y.size());
    for (int oy = 0; oy < sh.out_h; ++oy)
      for (int ox = 0; ox < sh.out_w; ++ox)
        for (int ch = 0; ch < c; ++ch) {
          double acc = b[ch];
          for (int ky = 0; ky < k; ++ky)
            for (int kx = 0; kx < k; ++kx) {
              const int iy = oy * s + ky - pt, ix = ox * s + kx - pl;
              if (iy < 0 || ix < 0 || iy >= h || ix >= w) continue;
              acc += double(x[(iy * w + ix) * c + ch]) * wt[(ky * k + kx) * c + ch];
            }
          want[(size_t(oy) * sh.out_w + ox) * c + ch] = act_d(acc, act);
        }
    expect_close(y, want, 1e-5);
  }
}

TEST(RefKernels, LinearMatchesDirectFormula) {
  std::mt19937 g(3);
  for (int round = 0; round < 40; ++round) {
    const GemmShape s{1 + int(g() % 37), 1 + int(g() % 41), 1 + int(g() % 53)};
    const auto x = rnd(size_t(s.m) * s.k, g), w = rnd(size_t(s.n) * s.k, g),
               b = rnd(size_t(s.n), g), r = rnd(size_t(s.m) * s.n, g);
    const Act act = Act(g() % 5);
    const bool with_res = g() % 2;
    std::vector<float> y(size_t(s.m) * s.n);
    f32_linear__ref(s, x.data(), w.data(), b.data(), with_res ? r.data() : nullptr, act, y.data());
    std::vector<double> want(y.size());
    for (int i = 0; i < s.m; ++i)
      for (int j = 0; j < s.n; ++j) {
        double acc = b[j];
        for (int p = 0; p < s.k; ++p) acc += double(x[i * s.k + p]) * w[j * s.k + p];
        want[size_t(i) * s.n + j] = act_d(acc, act) + (with_res ? r[size_t(i) * s.n + j] : 0.0);
      }
    expect_close(y, want, 1e-5);
  }
}

TEST(RefKernels, LayerNormMatchesDirectFormula) {
  std::mt19937 g(4);
  for (int round = 0; round < 20; ++round) {
    const int rows = 1 + int(g() % 9), n = 1 + int(g() % 300);
    auto x = rnd(size_t(rows) * n, g, 3.0f);
    for (auto& v : x) v += 5.0f;  // a large mean stresses the variance computation
    const auto gm = rnd(size_t(n), g), bt = rnd(size_t(n), g);
    std::vector<float> y(x.size());
    f32_layernorm__ref(rows, n, x.data(), gm.data(), bt.data(), 1e-5f, y.data());
    std::vector<double> want(y.size());
    for (int r = 0; r < rows; ++r) {
      double m = 0, v = 0;
      for (int i = 0; i < n; ++i) m += x[r * n + i];
      m /= n;
      for (int i = 0; i < n; ++i) v += (x[r * n + i] - m) * (x[r * n + i] - m);
      v /= n;
      for (int i = 0; i < n; ++i)
        want[r * n + i] = (x[r * n + i] - m) / std::sqrt(v + 1e-5) * gm[i] + bt[i];
    }
    expect_close(y, want, 1e-5);
  }
}

TEST(RefKernels, AttentionMatchesFullScoreMatrix) {
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

TEST(RefKernels, SqueezeExciteMatchesDirectFormula) {
  std::mt19937 g(6);
  for (int round = 0; round < 20; ++round) {
    const int px = 1 + int(g() % 50), c = 1 + int(g() % 40), cr = 1 + int(g() % 10);
    const auto x = rnd(size_t(px) * c, g), w1 = rnd(size_t(cr) * c, g), b1 = rnd(size_t(cr), g),
               w2 = rnd(size_t(c) * cr, g), b2 = rnd(size_t(c), g);
    std::vector<float> y(x.size()), scratch(f32_squeeze_excite__ref_scratch(c, cr));
    f32_squeeze_excite__ref(px, c, cr, x.data(), w1.data(), b1.data(), w2.data(), b2.data(),
                            y.data(), scratch.data());
    std::vector<double> mean(c, 0.0), red(cr), gate(c), want(y.size());
    for (int p = 0; p < px; ++p)
      for (int ch = 0; ch < c; ++ch) mean[ch] += x[p * c + ch] / double(px);
    for (int r = 0; r < cr; ++r) {
      double a = b1[r];
      for (int ch = 0; ch < c; ++ch) a += w1[r * c + ch] * mean[ch];
      red[r] = act_d(a, Act::kSilu);
    }
    for (int ch = 0; ch < c; ++ch) {
      double a = b2[ch];
      for (int r = 0; r < cr; ++r) a += w2[ch * cr + r] * red[r];
      gate[ch] = act_d(a, Act::kSigmoid);
    }
    for (int p = 0; p < px; ++p)
      for (int ch = 0; ch < c; ++ch) want[p * c + ch] = x[p * c + ch] * gate[ch];
    expect_close(y, want, 1e-5);
    // In place (y aliases x) gives the same.
    auto inplace = x;
    f32_squeeze_excite__ref(px, c, cr, inplace.data(), w1.data(), b1.data(), w2.data(), b2.data(),
                            inplace.data(), scratch.data());
    EXPECT_EQ(inplace, y);
  }
}

TEST(RefKernels, ElementwiseAndConcat) {
  std::mt19937 g(7);
  const auto a = rnd(101, g, 10.0f), b = rnd(101, g);
  std::vector<float> y(101);
  f32_add__ref(101, a.data(), b.data(), y.data());
  for (int i = 0; i < 101; ++i) EXPECT_EQ(y[i], a[i] + b[i]);
  for (int act = 0; act < 5; ++act) {
    f32_activation__ref(101, Act(act), a.data(), y.data());
    for (int i = 0; i < 101; ++i)
      EXPECT_NEAR(y[i], act_d(a[i], Act(act)), 1e-5 * (1 + std::fabs(a[i])));
  }
  const float r0[6] = {1, 2, 3, 4, 5, 6}, r1[4] = {7, 8, 9, 10};
  const float* xs[2] = {r0, r1};
  const int widths[2] = {3, 2};
  float out[10];
  f32_concat_rows__ref(2, 2, xs, widths, out);
  const float want[10] = {1, 2, 3, 7, 8, 4, 5, 6, 9, 10};
  for (int i = 0; i < 10; ++i) EXPECT_EQ(out[i], want[i]);
}

// The single-query algebra against the plain path: project the memory to keys
// and values, then attend.
TEST(RefKernels, CrossAttentionOneQueryEqualsProjectThenAttend) {
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
    f32_linear__ref({l, e, e}, keys_in.data(), wk.data(), bk.data(), nullptr, Act::kNone, k.data());
    f32_linear__ref({l, e, e}, m.data(), wv.data(), bv.data(), nullptr, Act::kNone, v.data());
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

}  // namespace
}  // namespace aprt::kernels
