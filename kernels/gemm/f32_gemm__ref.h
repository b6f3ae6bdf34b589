#pragma once

#include "kernels/common/kernel_types.h"

namespace aprt::kernels {

// Y[m][n] = act(sum_k X[m][k] * W[n][k] + bias[n]) + residual[m][n].
// bias and residual may be null. Also the 1x1 convolution on NHWC maps.
void f32_gemm__ref(const GemmShape& s, const float* x, const float* w, const float* bias,
                   const float* residual, Act act, float* y);

}  // namespace aprt::kernels
