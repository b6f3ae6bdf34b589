// The single-query cross-attention's scores (f32_cross_scores_impl.inl), one
// translation unit per ISA (kernels/simd/isa.h).
#include "kernels/table/simd_kernels.h"

namespace aprt::kernels {
namespace APRT_SIMD {
// clang-format off
#include APRT_SIMD_VEC
#include "kernels/simd/vmath.inl"
#include "kernels/attention/f32_cross_scores_impl.inl"
// clang-format on
}  // namespace APRT_SIMD

void APRT_SIMD_NAME(f32_cross_scores, )(int e, int heads, const float* m, const float* pos,
                                        const float* qt, float* s, size_t ls, int j0, int j1) {
  APRT_SIMD::cross_scores(e, heads, m, pos, qt, s, ls, j0, j1);
}

}  // namespace aprt::kernels
