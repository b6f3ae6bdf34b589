// The int8 GEMM family (kernels/gemm/qs8_gemm.h) against its reference, bit
// for bit, on random odd shapes, for every int8 part this CPU can run: every
// epilogue, called whole and in row/panel pieces as the thread pool splits
// it, and the quantiser on halfway values, huge values, infinities and NaN.
#include "kernels/gemm/qs8_gemm.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "kernels/gemm/qu8s8_gemm__ref.h"
#include "tests/kernels/kernel_test_support.h"

namespace aprt::kernels {
namespace {

using namespace aprt::kernels::testing;

class QGemmKernels : public Qs8KernelTest {};

TEST_P(QGemmKernels, GemmBitExactOnOddShapes) {
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

TEST_P(QGemmKernels, QuantizeBitExact) {
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

INSTANTIATE_TEST_SUITE_P(Isa, QGemmKernels, ::testing::ValuesIn(qs8_cases()), case_name<Qs8Case>);

}  // namespace
}  // namespace aprt::kernels
