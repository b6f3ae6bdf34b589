#include "kernels/rowwise/f32_elementwise__ref.h"

#include <cmath>
#include <cstring>

#include "kernels/rowwise/activation__ref.h"

namespace aprt::kernels {

void f32_add__ref(size_t n, const float* a, const float* b, float* y) {
  for (size_t i = 0; i < n; ++i) y[i] = a[i] + b[i];
}

void f32_softmax_rows__ref(int n, float* x, int r0, int r1) {
  for (int r = r0; r < r1; ++r) {
    float* row = x + size_t(r) * n;
    float m = row[0];
    for (int i = 1; i < n; ++i) m = row[i] > m ? row[i] : m;
    float sum = 0.0f;
    for (int i = 0; i < n; ++i) {
      row[i] = std::exp(row[i] - m);
      sum += row[i];
    }
    const float inv = 1.0f / sum;
    for (int i = 0; i < n; ++i) row[i] *= inv;
  }
}

void f32_activation__ref(size_t n, Act act, const float* x, float* y) {
  for (size_t i = 0; i < n; ++i) y[i] = ref::apply_act(x[i], act);
}

void f32_concat_rows__ref(int rows, int count, const float* const* xs, const int* widths,
                          float* y) {
  for (int r = 0; r < rows; ++r) {
    for (int i = 0; i < count; ++i) {
      std::memcpy(y, xs[i] + static_cast<size_t>(r) * widths[i], sizeof(float) * widths[i]);
      y += widths[i];
    }
  }
}

}  // namespace aprt::kernels
