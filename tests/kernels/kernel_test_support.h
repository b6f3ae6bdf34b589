// What the kernel families' tests (tests/kernels/<family>/) share: every
// part of the kernel table this build contains as a test parameter (a part
// this CPU cannot run is skipped, and says so), random data, tolerances.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <ostream>
#include <random>
#include <string>
#include <vector>

#include "kernels/table/kernel_table.h"

namespace aprt::kernels::testing {

// An fp32 or int8 part of the table, by name.
template <class Part>
struct PartCase {
  std::string name;
  const Part* part;
  bool runs;
  friend void PrintTo(const PartCase& c, std::ostream* os) { *os << c.name; }
};
using F32Case = PartCase<KernelSet>;
using Qs8Case = PartCase<QKernelSet>;

inline std::vector<F32Case> f32_cases() {
  std::vector<F32Case> out;
  for (const IsaParts& p : isa_parts()) out.push_back({p.isa, p.f32, p.f32_runs});
  if (out.empty()) out.push_back({"none", nullptr, false});  // a build with no fast kernels
  return out;
}

inline std::vector<Qs8Case> qs8_cases() {
  std::vector<Qs8Case> out;
  for (const IsaParts& p : isa_parts()) {
    for (int i = 0; i < 2; ++i) {
      if (!p.qs8[i]) continue;
      bool seen = false;
      for (const Qs8Case& c : out) seen = seen || c.part == p.qs8[i];
      if (!seen) out.push_back({p.qs8[i]->isa, p.qs8[i], p.qs8_runs[i]});
    }
  }
  if (out.empty()) out.push_back({"none", nullptr, false});
  return out;
}

template <class Case>
std::string case_name(const ::testing::TestParamInfo<Case>& info) {
  return info.param.name;
}

// A fixture over one fp32 part; each family derives its own (one suite name
// per family) and instantiates it over f32_cases().
class F32KernelTest : public ::testing::TestWithParam<F32Case> {
 protected:
  void SetUp() override {
    ks_ = GetParam().part;
    if (!ks_) GTEST_SKIP() << "no fast kernels in this build";
    if (!GetParam().runs) GTEST_SKIP() << "this CPU cannot run " << GetParam().name;
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

// The same over one int8 part.
class Qs8KernelTest : public ::testing::TestWithParam<Qs8Case> {
 protected:
  void SetUp() override {
    ks_ = GetParam().part;
    if (!ks_) GTEST_SKIP() << "no int8 kernels in this build";
    if (!GetParam().runs) GTEST_SKIP() << "this CPU cannot run " << GetParam().name;
  }
  const QKernelSet* ks_ = nullptr;
};

inline void expect_near_all(const std::vector<float>& got, const std::vector<float>& want,
                            double tol, const std::string& what) {
  ASSERT_EQ(got.size(), want.size());
  for (size_t i = 0; i < got.size(); ++i) {
    ASSERT_NEAR(got[i], want[i], tol * (1.0 + std::fabs(want[i]))) << what << " at " << i;
  }
}

// For the references against formulas written out: n values in [-s, s].
inline std::vector<float> rnd(size_t n, std::mt19937& g, float s = 1.0f) {
  std::uniform_real_distribution<float> u(-s, s);
  std::vector<float> v(n);
  for (auto& x : v) x = u(g);
  return v;
}

inline double act_d(double x, Act a) {
  switch (a) {
    case Act::kNone: return x;
    case Act::kSilu: return x / (1 + std::exp(-x));
    case Act::kGelu: return 0.5 * x * (1 + std::erf(x / std::sqrt(2.0)));
    case Act::kSigmoid: return 1 / (1 + std::exp(-x));
    case Act::kRelu: return x > 0 ? x : 0;
  }
  return x;
}

inline void expect_close(const std::vector<float>& got, const std::vector<double>& want,
                         double tol) {
  ASSERT_EQ(got.size(), want.size());
  for (size_t i = 0; i < got.size(); ++i) {
    ASSERT_NEAR(got[i], want[i], tol * (1 + std::fabs(want[i]))) << "at " << i;
  }
}

// Output size under explicit (t, l) padding and total padding (pt+pb, pl+pr).
inline Conv2dShape conv_shape(int h, int w, int ci, int co, int kh, int kw, int s, int pt, int pl,
                              int pb, int pr) {
  return {h, w,  ci, (h + pt + pb - kh) / s + 1, (w + pl + pr - kw) / s + 1, co, kh, kw, s,
          s, pt, pl};
}

}  // namespace aprt::kernels::testing
