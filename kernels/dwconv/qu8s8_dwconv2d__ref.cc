#include "kernels/dwconv/qu8s8_dwconv2d__ref.h"

#include <cmath>
#include <cstddef>

#include "kernels/rowwise/activation__ref.h"

namespace aprt::kernels {

void qu8s8_dwconv2d__ref(const Conv2dShape& s, const uint8_t* x, int32_t a_zero, const int8_t* w,
                         const float* mult, const float* bias, Act act, float* y) {
  const int C = s.in_c;
  for (int oy = 0; oy < s.out_h; ++oy) {
    for (int ox = 0; ox < s.out_w; ++ox) {
      for (int c = 0; c < C; ++c) {
        int32_t acc = 0;
        for (int ky = 0; ky < s.kernel_h; ++ky) {
          const int iy = oy * s.stride_h - s.pad_top + ky;
          if (iy < 0 || iy >= s.in_h) continue;
          for (int kx = 0; kx < s.kernel_w; ++kx) {
            const int ix = ox * s.stride_w - s.pad_left + kx;
            if (ix < 0 || ix >= s.in_w) continue;
            acc += (int32_t(x[(size_t(iy) * s.in_w + ix) * C + c]) - a_zero) *
                   int32_t(w[(ky * s.kernel_w + kx) * C + c]);
          }
        }
        const float v = std::fma(float(acc), mult[c], bias[c]);
        y[(size_t(oy) * s.out_w + ox) * C + c] = ref::apply_act(v, act);
      }
    }
  }
}

}  // namespace aprt::kernels
