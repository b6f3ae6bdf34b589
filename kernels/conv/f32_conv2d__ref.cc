#include "kernels/conv/f32_conv2d__ref.h"

#include "kernels/rowwise/activation__ref.h"

namespace aprt::kernels {

void f32_conv2d__ref(const Conv2dShape& s, const float* x, const float* w, const float* bias,
                     const float* residual, Act act, float* y) {
  for (int oy = 0; oy < s.out_h; ++oy) {
    for (int ox = 0; ox < s.out_w; ++ox) {
      for (int co = 0; co < s.out_c; ++co) {
        float acc = bias ? bias[co] : 0.0f;
        for (int ky = 0; ky < s.kernel_h; ++ky) {
          const int iy = oy * s.stride_h + ky - s.pad_top;
          if (iy < 0 || iy >= s.in_h) continue;
          for (int kx = 0; kx < s.kernel_w; ++kx) {
            const int ix = ox * s.stride_w + kx - s.pad_left;
            if (ix < 0 || ix >= s.in_w) continue;
            const float* xp = x + (iy * s.in_w + ix) * s.in_c;
            const float* wp = w + ((co * s.kernel_h + ky) * s.kernel_w + kx) * s.in_c;
            for (int ci = 0; ci < s.in_c; ++ci) acc += xp[ci] * wp[ci];
          }
        }
        const int o = (oy * s.out_w + ox) * s.out_c + co;
        float v = ref::apply_act(acc, act);
        if (residual) v += residual[o];
        y[o] = v;
      }
    }
  }
}

}  // namespace aprt::kernels
