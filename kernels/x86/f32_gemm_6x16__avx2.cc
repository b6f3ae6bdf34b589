// f32 GEMM, 6x16 register tile (rows x columns), avx2. See simd/gemm_impl.inl.
#include <immintrin.h>

#include <cstdint>

#include "kernels/common/kernel_types.h"

namespace aprt::kernels {
namespace avx2 {
// Order matters: the vector header, then vmath, then the kernels.
// clang-format off
#include "kernels/simd/vec_avx2.h"
#include "kernels/simd/vmath.inl"
#include "kernels/simd/gemm_impl.inl"
// clang-format on
}  // namespace avx2

void f32_gemm_6x16__avx2(const GemmArgs& g, int r0, int r1, int p0, int p1) {
  avx2::gemm_range<6, 2>(g, r0, r1, p0, p1);
}

}  // namespace aprt::kernels
