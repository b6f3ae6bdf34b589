#pragma once

#include "kernels/common/kernel_types.h"

namespace aprt::kernels {

// y = act(conv(x, w) + bias) + residual. Dense NHWC convolution with zero
// padding (pad_top/pad_left explicit, bottom/right implied by out_h/out_w).
// `residual` may be null; it has y's shape.
void f32_conv2d__ref(const Conv2dShape& s, const float* x, const float* w, const float* bias,
                     const float* residual, Act act, float* y);

}  // namespace aprt::kernels
