// int8 depthwise convolution, avx2: kernels/simd/qdwconv_impl.inl.
#include <immintrin.h>

#include <cstddef>
#include <cstdint>

#include "kernels/common/qkernel_set.h"

namespace aprt::kernels {
namespace avx2 {
// clang-format off
#include "kernels/simd/vec_avx2.h"
#include "kernels/simd/vmath.inl"
#include "kernels/simd/qdwconv_impl.inl"
// clang-format on
}  // namespace avx2

void qu8s8_dwconv__avx2(const QDwConvArgs& a, int oy0, int oy1) {
  avx2::qdwconv_rows(a, oy0, oy1);
}

}  // namespace aprt::kernels
