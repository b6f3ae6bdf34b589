// f32 GEMM, 8x12 register tile (rows x columns), neon. See simd/gemm_impl.inl.
#include <arm_neon.h>

#include <cstdint>

#include "kernels/common/kernel_types.h"

namespace aprt::kernels {
namespace neon {
// Order matters: the vector header, then vmath, then the kernels.
// clang-format off
#include "kernels/simd/vec_neon.h"
#include "kernels/simd/vmath.inl"
#include "kernels/simd/gemm_impl.inl"
// clang-format on
}  // namespace neon

void f32_gemm_8x12__neon(const GemmArgs& g, int r0, int r1, int p0, int p1) {
  neon::gemm_range<8, 3>(g, r0, r1, p0, p1);
}

}  // namespace aprt::kernels
