// int8 depthwise convolution, the scalar reference of qu8s8_dwconv__<isa>
// (kernels/gemm/qs8_gemm.h has the scheme): exact int32 accumulation of
// (x - a_zero) * w over the taps inside the image (zero padding in real
// values), y = act(fma(acc, mult[c], bias[c])).
#pragma once

#include <cstdint>

#include "kernels/common/kernel_types.h"

namespace aprt::kernels {

void qu8s8_dwconv2d__ref(const Conv2dShape& s, const uint8_t* x, int32_t a_zero, const int8_t* w,
                         const float* mult, const float* bias, Act act, float* y);

}  // namespace aprt::kernels
