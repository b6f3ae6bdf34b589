// int8 depthwise convolution, neon: kernels/simd/qdwconv_impl.inl.
#include <arm_neon.h>

#include <cstddef>
#include <cstdint>

#include "kernels/common/qkernel_set.h"

namespace aprt::kernels {
namespace neon {
// clang-format off
#include "kernels/simd/vec_neon.h"
#include "kernels/simd/vmath.inl"
#include "kernels/simd/qdwconv_impl.inl"
// clang-format on
}  // namespace neon

void qu8s8_dwconv__neon(const QDwConvArgs& a, int oy0, int oy1) {
  neon::qdwconv_rows(a, oy0, oy1);
}

}  // namespace aprt::kernels
