// f32 GEMM, 8x32 register tile (rows x columns), avx512. See simd/gemm_impl.inl.
#include <immintrin.h>

#include <cstdint>

#include "kernels/common/kernel_types.h"

namespace aprt::kernels {
namespace avx512 {
// Order matters: the vector header, then vmath, then the kernels.
// clang-format off
#include "kernels/simd/vec_avx512.h"
#include "kernels/simd/vmath.inl"
#include "kernels/simd/gemm_impl.inl"
// clang-format on
}  // namespace avx512

void f32_gemm_8x32__avx512(const GemmArgs& g, int r0, int r1, int p0, int p1) {
  avx512::gemm_range<8, 2>(g, r0, r1, p0, p1);
}

}  // namespace aprt::kernels
