#include "kernels/dwconv/f32_dwconv2d__ref.h"

#include "kernels/rowwise/activation__ref.h"

namespace aprt::kernels {

void f32_dwconv2d__ref(const Conv2dShape& s, const float* x, const float* w, const float* bias,
                       Act act, float* y) {
  const int c = s.in_c;
  for (int oy = 0; oy < s.out_h; ++oy) {
    for (int ox = 0; ox < s.out_w; ++ox) {
      for (int ch = 0; ch < c; ++ch) {
        float acc = bias ? bias[ch] : 0.0f;
        for (int ky = 0; ky < s.kernel_h; ++ky) {
          const int iy = oy * s.stride_h + ky - s.pad_top;
          if (iy < 0 || iy >= s.in_h) continue;
          for (int kx = 0; kx < s.kernel_w; ++kx) {
            const int ix = ox * s.stride_w + kx - s.pad_left;
            if (ix < 0 || ix >= s.in_w) continue;
            acc += x[(iy * s.in_w + ix) * c + ch] * w[(ky * s.kernel_w + kx) * c + ch];
          }
        }
        y[(oy * s.out_w + ox) * c + ch] = ref::apply_act(acc, act);
      }
    }
  }
}

}  // namespace aprt::kernels
