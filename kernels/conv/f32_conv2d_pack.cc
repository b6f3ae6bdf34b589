#include <cstddef>

#include "kernels/table/kernel_table.h"

namespace aprt::kernels {

void f32_conv2d_pack_weights(int co, int kh, int kw, int ci, const float* w, float* out) {
  for (int o = 0; o < co; ++o) {
    for (int y = 0; y < kh; ++y) {
      for (int x = 0; x < kw; ++x) {
        for (int i = 0; i < ci; ++i) {
          out[((size_t(y) * kw + x) * ci + i) * co + o] =
              w[((size_t(o) * kh + y) * kw + x) * ci + i];
        }
      }
    }
  }
}

}  // namespace aprt::kernels
