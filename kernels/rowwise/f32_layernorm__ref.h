#pragma once

namespace aprt::kernels {

// Each of the `rows` rows of `n` values: (x - mean) / sqrt(var + eps) * gamma + beta,
// with the biased variance (as PyTorch). Accumulates in double.
void f32_layernorm__ref(int rows, int n, const float* x, const float* gamma, const float* beta,
                        float eps, float* y);

}  // namespace aprt::kernels
