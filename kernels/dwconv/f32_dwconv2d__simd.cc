// f32 depthwise NHWC convolution (f32_dwconv2d_impl.inl), one translation unit
// per ISA (kernels/simd/isa.h).
#include "kernels/table/simd_kernels.h"

namespace aprt::kernels {
namespace APRT_SIMD {
// clang-format off
#include APRT_SIMD_VEC
#include "kernels/simd/vmath.inl"
#include "kernels/dwconv/f32_dwconv2d_impl.inl"
// clang-format on
}  // namespace APRT_SIMD

void APRT_SIMD_NAME(f32_dwconv2d, )(const Conv2dShape& s, const float* x, const float* w,
                                    const float* bias, Act act, float* y, int oy0, int oy1) {
  APRT_SIMD::dwconv_rows(s, x, w, bias, int(act), y, oy0, oy1);
}

}  // namespace aprt::kernels
