#include "kernels/gemm/qu8s8_gemm__ref.h"

#include <cmath>

namespace aprt::kernels {

void qu8s8_gemm__ref(int m, int n, int k, const uint8_t* a, size_t lda, int32_t a_zero,
                     const int8_t* w, const float* mult, const float* bias, const float* residual,
                     size_t ldr, Act act, float* c, size_t ldc) {
  for (int i = 0; i < m; ++i) {
    for (int j = 0; j < n; ++j) {
      int32_t acc = 0;
      for (int p = 0; p < k; ++p) {
        acc += (int32_t(a[size_t(i) * lda + p]) - a_zero) * int32_t(w[size_t(j) * k + p]);
      }
      // One fused multiply-add: what every kernel's epilogue does.
      float y = std::fma(float(acc), mult[j], bias ? bias[j] : 0.0f);
      if (residual) y += residual[size_t(i) * ldr + j];
      if (act == Act::kRelu) y = y > 0.0f ? y : 0.0f;  // -0 and NaN give +0, as vmax(y, 0) does
      c[size_t(i) * ldc + j] = y;
    }
  }
}

void f32_qu8_quantize__ref(size_t n, const float* x, float inv_scale, int32_t zero, uint8_t* q) {
  for (size_t i = 0; i < n; ++i) {
    // nearbyint: round half to even in the default rounding mode, as the
    // vector conversions do.
    float v = std::nearbyint(x[i] * inv_scale) + float(zero);
    v = v > 0.0f ? (v > 255.0f ? 255.0f : v) : 0.0f;  // NaN -> 0
    q[i] = uint8_t(v);
  }
}

}  // namespace aprt::kernels
