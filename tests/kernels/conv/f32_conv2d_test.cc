// The dense convolution: the reference against the formula written out,
// every ISA against the reference on random odd shapes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "kernels/conv/f32_conv2d__ref.h"
#include "tests/kernels/kernel_test_support.h"

namespace aprt::kernels {
namespace {

using namespace aprt::kernels::testing;

class Conv2dKernels : public F32KernelTest {};

TEST(Conv2dRef, Conv2dMatchesDirectFormula) {
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

TEST_P(Conv2dKernels, DenseConvolution) {
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

INSTANTIATE_TEST_SUITE_P(Isa, Conv2dKernels, ::testing::ValuesIn(f32_cases()), case_name<F32Case>);

}  // namespace
}  // namespace aprt::kernels
