#pragma once

#include "kernels/common/kernel_types.h"

namespace aprt::kernels {

// y = act(depthwise_conv(x, w) + bias). NHWC; w is [kernel_h][kernel_w][c];
// s.in_c == s.out_c.
void f32_dwconv2d__ref(const Conv2dShape& s, const float* x, const float* w, const float* bias,
                       Act act, float* y);

}  // namespace aprt::kernels
