// The int8 GEMM epilogue both NEON kernels share (kernels/gemm/qs8_gemm.h):
// exact = acc - zero * colsum, y = fma(float(exact), mult, bias) (+ residual,
// ReLU), stored for the tile's valid columns. `zero` is the activation zero
// point as the kernel's accumulator sees it. Static: each kernel's translation
// unit (one of them built with +dotprod) keeps its own copy.
#pragma once

#include <arm_neon.h>

#include "kernels/gemm/qs8_gemm.h"

namespace aprt::kernels {

template <int R>
static inline void qgemm_store_neon(const QGemmArgs& g, int r0, int j0, int ncols,
                                    const int32x4_t (&acc)[R][4], int32_t zero) {
  for (int q = 0; q < 4; ++q) {
    const int cols = ncols - 4 * q;
    if (cols <= 0) break;
    const int j = j0 + 4 * q;
    int32_t cs[4] = {};
    float mu[4] = {}, bi[4] = {};
    for (int t = 0; t < cols && t < 4; ++t) {
      cs[t] = g.w_colsum[j + t];
      mu[t] = g.mult[j + t];
      bi[t] = g.bias ? g.bias[j + t] : 0.0f;
    }
    const int32x4_t corr = vmulq_n_s32(vld1q_s32(cs), zero);
    const float32x4_t mult = vld1q_f32(mu), bias = vld1q_f32(bi);
    for (int r = 0; r < R; ++r) {
      const float32x4_t y = vfmaq_f32(bias, vcvtq_f32_s32(vsubq_s32(acc[r][q], corr)), mult);
      float out[4];
      vst1q_f32(out, y);
      const float* res = g.residual ? g.residual + size_t(r0 + r) * g.ldr + j : nullptr;
      float* c = g.c + size_t(r0 + r) * g.ldc + j;
      for (int t = 0; t < cols && t < 4; ++t) {
        float v = out[t];
        if (res) v += res[t];
        if (g.act == Act::kRelu) v = v > 0.0f ? v : 0.0f;
        c[t] = v;
      }
    }
  }
}

}  // namespace aprt::kernels
