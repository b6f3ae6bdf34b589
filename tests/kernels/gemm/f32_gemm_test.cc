// The fp32 GEMM family: the reference against the formula written out, every
// ISA's tiles against the reference on random odd shapes.
#include "kernels/gemm/f32_gemm.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "kernels/gemm/f32_gemm__ref.h"
#include "tests/kernels/kernel_test_support.h"

namespace aprt::kernels {
namespace {

using namespace aprt::kernels::testing;

class GemmKernels : public F32KernelTest {};

TEST(GemmRef, LinearMatchesDirectFormula) {
  std::mt19937 g(3);
  for (int round = 0; round < 40; ++round) {
    const GemmShape s{1 + int(g() % 37), 1 + int(g() % 41), 1 + int(g() % 53)};
    const auto x = rnd(size_t(s.m) * s.k, g), w = rnd(size_t(s.n) * s.k, g),
               b = rnd(size_t(s.n), g), r = rnd(size_t(s.m) * s.n, g);
    const Act act = Act(g() % 5);
    const bool with_res = g() % 2;
    std::vector<float> y(size_t(s.m) * s.n);
    f32_gemm__ref(s, x.data(), w.data(), b.data(), with_res ? r.data() : nullptr, act, y.data());
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

TEST_P(GemmKernels, GemmWithPackedWeights) {
  for (int round = 0; round < 60; ++round) {
    const int m = pick(1, 40), n = pick(1, 3 * ks_->gemm_nr + 5), k = pick(1, 300);
    const Act act = Act(pick(0, 4));
    const bool with_bias = pick(0, 1), with_res = pick(0, 1);
    const auto x = rnd(size_t(m) * k), w = rnd(size_t(n) * k, 0.3f), b = rnd(n),
               r = rnd(size_t(m) * n);
    std::vector<float> want(size_t(m) * n), got(size_t(m) * n, -7.0f);
    f32_gemm__ref({m, n, k}, x.data(), w.data(), with_bias ? b.data() : nullptr,
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

TEST_P(GemmKernels, GemmWithRowMajorB) {
  for (int round = 0; round < 40; ++round) {
    const int m = pick(1, 20), n = pick(1, 2 * ks_->gemm_nr + 7), k = pick(1, 200);
    const auto x = rnd(size_t(m) * k), w = rnd(size_t(n) * k);
    // B = W^T as a plain [k][n] matrix, exactly sized (the tail panel must not over-read).
    std::vector<float> bt(size_t(k) * n);
    for (int j = 0; j < n; ++j)
      for (int p = 0; p < k; ++p) bt[size_t(p) * n + j] = w[size_t(j) * k + p];
    std::vector<float> want(size_t(m) * n), got(size_t(m) * n);
    f32_gemm__ref({m, n, k}, x.data(), w.data(), nullptr, nullptr, Act::kNone, want.data());
    GemmArgs g{
        m,     n,       k,       x.data(), size_t(k),  bt.data(), size_t(n), size_t(ks_->gemm_nr),
        false, nullptr, nullptr, 0,        got.data(), size_t(n), Act::kNone};
    ks_->gemm(g, 0, m, 0, (n + ks_->gemm_nr - 1) / ks_->gemm_nr);
    expect_near_all(got, want, 2e-5, "gemm row-major B");
  }
}

INSTANTIATE_TEST_SUITE_P(Isa, GemmKernels, ::testing::ValuesIn(f32_cases()), case_name<F32Case>);

}  // namespace
}  // namespace aprt::kernels
