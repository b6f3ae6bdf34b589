// int8 depthwise convolution, avx512: kernels/simd/qdwconv_impl.inl.
#include <immintrin.h>

#include <cstddef>
#include <cstdint>

#include "kernels/common/qkernel_set.h"

namespace aprt::kernels {
namespace avx512 {
// clang-format off
#include "kernels/simd/vec_avx512.h"
#include "kernels/simd/vmath.inl"
#include "kernels/simd/qdwconv_impl.inl"
// clang-format on
}  // namespace avx512

void qu8s8_dwconv__avx512(const QDwConvArgs& a, int oy0, int oy1) {
  avx512::qdwconv_rows(a, oy0, oy1);
}

}  // namespace aprt::kernels
