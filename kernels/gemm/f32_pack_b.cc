#include <cstring>

#include "kernels/common/kernel_types.h"

namespace aprt::kernels {

size_t f32_pack_b_floats(int n, int k, int nr) {
  return size_t((n + nr - 1) / nr) * size_t(k) * size_t(nr);
}

void f32_pack_b(int n, int k, int nr, const float* w, float* out) {
  const int panels = (n + nr - 1) / nr;
  std::memset(out, 0, f32_pack_b_floats(n, k, nr) * sizeof(float));
  for (int j = 0; j < panels; ++j) {
    for (int jj = 0; jj < nr && j * nr + jj < n; ++jj) {
      const float* row = w + size_t(j * nr + jj) * size_t(k);
      float* dst = out + size_t(j) * size_t(k) * size_t(nr) + jj;
      for (int p = 0; p < k; ++p) dst[size_t(p) * nr] = row[p];
    }
  }
}

}  // namespace aprt::kernels
