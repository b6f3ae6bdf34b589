// f32 depthwise and dense NHWC convolutions, avx512. See simd/dwconv_impl.inl, conv_impl.inl.
#include <immintrin.h>

#include <cstdint>

#include "kernels/common/kernel_types.h"

namespace aprt::kernels {
namespace avx512 {
// Order matters: the vector header, then vmath, then the kernels.
// clang-format off
#include "kernels/simd/vec_avx512.h"
#include "kernels/simd/vmath.inl"
#include "kernels/simd/conv_impl.inl"
#include "kernels/simd/dwconv_impl.inl"
// clang-format on
}  // namespace avx512

void f32_dwconv2d__avx512(const Conv2dShape& s, const float* x, const float* w, const float* bias,
                          Act act, float* y, int oy0, int oy1) {
  avx512::dwconv_rows(s, x, w, bias, int(act), y, oy0, oy1);
}

void f32_conv2d__avx512(const Conv2dShape& s, const float* x, const float* w, const float* bias,
                        const float* residual, Act act, float* y, int oy0, int oy1) {
  avx512::conv_rows(s, x, w, bias, residual, int(act), y, oy0, oy1);
}

}  // namespace aprt::kernels
