#include "kernels/gemm/f32_gemm__ref.h"

#include "kernels/rowwise/activation__ref.h"

namespace aprt::kernels {

void f32_gemm__ref(const GemmShape& s, const float* x, const float* w, const float* bias,
                   const float* residual, Act act, float* y) {
  for (int i = 0; i < s.m; ++i) {
    const float* xr = x + static_cast<size_t>(i) * s.k;
    for (int j = 0; j < s.n; ++j) {
      const float* wr = w + static_cast<size_t>(j) * s.k;
      float acc = 0.0f;
      for (int p = 0; p < s.k; ++p) acc += xr[p] * wr[p];
      if (bias) acc += bias[j];
      float v = ref::apply_act(acc, act);
      const size_t o = static_cast<size_t>(i) * s.n + j;
      if (residual) v += residual[o];
      y[o] = v;
    }
  }
}

}  // namespace aprt::kernels
