// f32 GEMM register tiles (f32_gemm_impl.inl), one translation unit per ISA
// (kernels/simd/isa.h): 8x32 on AVX-512, 6x16 on AVX2, 8x12 on NEON.
#include "kernels/table/simd_kernels.h"

namespace aprt::kernels {
namespace APRT_SIMD {
// Order matters: the vector header, then vmath, then the kernels.
// clang-format off
#include APRT_SIMD_VEC
#include "kernels/simd/vmath.inl"
#include "kernels/gemm/f32_gemm_impl.inl"
// clang-format on
}  // namespace APRT_SIMD

void APRT_SIMD_NAME(f32_gemm_, APRT_GEMM_TILE)(const GemmArgs& g, int r0, int r1, int p0, int p1) {
  APRT_SIMD::gemm_range<APRT_GEMM_MR, APRT_GEMM_NV>(g, r0, r1, p0, p1);
}

}  // namespace aprt::kernels
