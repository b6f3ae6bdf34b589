#pragma once

#include <cstddef>

namespace aprt::kernels {

// Squeeze-and-excitation on an NHWC map of `pixels` x `c`:
//   s = mean over pixels; r = silu(W1 s + b1) (W1 [cr][c]); e = sigmoid(W2 r + b2) (W2 [c][cr])
//   y = x * e (per channel). `scratch` holds c + cr floats. y may alias x.
size_t f32_squeeze_excite__ref_scratch(int c, int cr);
void f32_squeeze_excite__ref(int pixels, int c, int cr, const float* x, const float* w1,
                             const float* b1, const float* w2, const float* b2, float* y,
                             float* scratch);

}  // namespace aprt::kernels
