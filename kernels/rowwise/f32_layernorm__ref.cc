#include "kernels/rowwise/f32_layernorm__ref.h"

#include <cmath>
#include <cstddef>

namespace aprt::kernels {

void f32_layernorm__ref(int rows, int n, const float* x, const float* gamma, const float* beta,
                        float eps, float* y) {
  for (int r = 0; r < rows; ++r) {
    const float* xr = x + static_cast<size_t>(r) * n;
    float* yr = y + static_cast<size_t>(r) * n;
    double mean = 0.0;
    for (int i = 0; i < n; ++i) mean += xr[i];
    mean /= n;
    double var = 0.0;
    for (int i = 0; i < n; ++i) var += (xr[i] - mean) * (xr[i] - mean);
    var /= n;
    const double inv = 1.0 / std::sqrt(var + eps);
    for (int i = 0; i < n; ++i) {
      yr[i] = static_cast<float>((xr[i] - mean) * inv) * gamma[i] + beta[i];
    }
  }
}

}  // namespace aprt::kernels
