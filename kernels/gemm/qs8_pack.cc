#include <cstring>

#include "kernels/gemm/qs8_gemm.h"

namespace aprt::kernels {

size_t qs8_pack_w_bytes(int n, int k, int nr, int kgroup) {
  const size_t panels = size_t((n + nr - 1) / nr), groups = size_t((k + kgroup - 1) / kgroup);
  return panels * groups * size_t(nr) * size_t(kgroup);
}

void qs8_pack_w(int n, int k, int nr, int kgroup, const int8_t* w, int8_t* out) {
  const int panels = (n + nr - 1) / nr, groups = (k + kgroup - 1) / kgroup;
  std::memset(out, 0, qs8_pack_w_bytes(n, k, nr, kgroup));
  for (int pn = 0; pn < panels; ++pn) {
    for (int g = 0; g < groups; ++g) {
      int8_t* o = out + (size_t(pn) * groups + g) * size_t(nr) * kgroup;
      for (int jj = 0; jj < nr; ++jj) {
        const int j = pn * nr + jj;
        if (j >= n) break;
        for (int kk = 0; kk < kgroup; ++kk) {
          const int p = g * kgroup + kk;
          if (p < k) o[jj * kgroup + kk] = w[size_t(j) * k + p];
        }
      }
    }
  }
}

void qs8_column_sums(int n, int k, const int8_t* w, int32_t* colsum) {
  for (int j = 0; j < n; ++j) {
    int32_t s = 0;
    for (int p = 0; p < k; ++p) s += w[size_t(j) * k + p];
    colsum[j] = s;
  }
}

}  // namespace aprt::kernels
