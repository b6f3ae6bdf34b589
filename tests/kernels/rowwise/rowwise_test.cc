// Row-wise kernels -- LayerNorm, add, softmax, activations, squeeze-excite:
// references against formulas written out, every ISA against the references.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "kernels/rowwise/f32_elementwise__ref.h"
#include "kernels/rowwise/f32_layernorm__ref.h"
#include "kernels/rowwise/f32_squeeze_excite__ref.h"
#include "tests/kernels/kernel_test_support.h"

namespace aprt::kernels {
namespace {

using namespace aprt::kernels::testing;

class RowwiseKernels : public F32KernelTest {};

TEST(RowwiseRef, LayerNormMatchesDirectFormula) {
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

TEST(RowwiseRef, SqueezeExciteMatchesDirectFormula) {
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

TEST(RowwiseRef, ElementwiseAndConcat) {
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

// Widths of whole vector pairs on every ISA (multiples of 32) take the
// four-rows-interleaved path for each full group of four rows of a range:
// against the reference, and bit for bit against the one-row loop (a range
// of one row), which it claims to match operation for operation.
TEST_P(RowwiseKernels, LayerNormFourRowsMatchOneRow) {
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

TEST_P(RowwiseKernels, LayerNormAddActivation) {
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

TEST_P(RowwiseKernels, ActivationsOverTheirWholeRange) {
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

TEST_P(RowwiseKernels, SqueezeExcite) {
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

// Softmax rows (the cross-attention's fallback for heads of any width):
// the reference against the formula in double, every ISA against the
// reference on odd widths, large and small logits.
TEST(RowwiseRef, SoftmaxMatchesDirectFormula) {
  std::mt19937 g(11);
  for (int n : {1, 3, 17, 64, 197}) {
    std::vector<float> x = rnd(size_t(3) * n, g, 30.0f);
    std::vector<double> want(x.size());
    for (int r = 0; r < 3; ++r) {
      double m = -1e300, sum = 0;
      for (int i = 0; i < n; ++i) m = std::max(m, double(x[size_t(r) * n + i]));
      for (int i = 0; i < n; ++i) sum += std::exp(double(x[size_t(r) * n + i]) - m);
      for (int i = 0; i < n; ++i)
        want[size_t(r) * n + i] = std::exp(double(x[size_t(r) * n + i]) - m) / sum;
    }
    f32_softmax_rows__ref(n, x.data(), 0, 3);
    expect_close(x, want, 1e-5);
  }
}

TEST_P(RowwiseKernels, SoftmaxRows) {
  for (int iter = 0; iter < 30; ++iter) {
    const int n = pick(1, 300), rows = pick(1, 9);
    const float gain = iter % 2 ? 40.0f : 1.0f;
    std::vector<float> got = rnd(size_t(rows) * n, gain), want = got;
    const int r0 = pick(0, rows - 1), r1 = pick(r0 + 1, rows);
    ks_->softmax_rows(n, got.data(), r0, r1);
    f32_softmax_rows__ref(n, want.data(), r0, r1);
    expect_near_all(got, want, 2e-6, "softmax n=" + std::to_string(n));
  }
}

INSTANTIATE_TEST_SUITE_P(Isa, RowwiseKernels, ::testing::ValuesIn(f32_cases()), case_name<F32Case>);

}  // namespace
}  // namespace aprt::kernels
