// int8 depthwise convolution (qu8s8_dwconv2d_impl.inl), one translation unit
// per ISA (kernels/simd/isa.h): the int8 tables' dwconv_rows.
#include "kernels/dwconv/qu8s8_dwconv2d.h"
#include "kernels/simd/isa.h"

namespace aprt::kernels {
namespace APRT_SIMD {
// clang-format off
#include APRT_SIMD_VEC
#include "kernels/simd/vmath.inl"
#include "kernels/dwconv/qu8s8_dwconv2d_impl.inl"
// clang-format on
}  // namespace APRT_SIMD

void APRT_SIMD_NAME(qu8s8_dwconv2d, )(const QDwConvArgs& a, int oy0, int oy1) {
  APRT_SIMD::qdwconv_rows(a, oy0, oy1);
}

}  // namespace aprt::kernels
