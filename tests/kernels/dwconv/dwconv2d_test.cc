// The depthwise convolutions: the fp32 reference against the formula
// written out, every ISA against it; the int8 kernels bit for bit against
// theirs on odd channel counts, kernel sizes, strides and asymmetric padding.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "kernels/dwconv/f32_dwconv2d__ref.h"
#include "kernels/dwconv/qu8s8_dwconv2d.h"
#include "kernels/dwconv/qu8s8_dwconv2d__ref.h"
#include "tests/kernels/kernel_test_support.h"

namespace aprt::kernels {
namespace {

using namespace aprt::kernels::testing;

class DwConv2dKernels : public F32KernelTest {};
class QDwConv2dKernels : public Qs8KernelTest {};

TEST(DwConv2dRef, DepthwiseMatchesDirectFormula) {
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

TEST_P(DwConv2dKernels, DepthwiseConvolution) {
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

TEST_P(QDwConv2dKernels, DwConvBitExactOnOddShapes) {
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

INSTANTIATE_TEST_SUITE_P(Isa, DwConv2dKernels, ::testing::ValuesIn(f32_cases()),
                         case_name<F32Case>);

INSTANTIATE_TEST_SUITE_P(Isa, QDwConv2dKernels, ::testing::ValuesIn(qs8_cases()),
                         case_name<Qs8Case>);

}  // namespace
}  // namespace aprt::kernels
