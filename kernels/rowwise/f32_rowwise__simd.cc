// f32 LayerNorm, add, softmax, activations and squeeze-excite
// (f32_rowwise_impl.inl), one translation unit per ISA (kernels/simd/isa.h).
#include "kernels/table/simd_kernels.h"

namespace aprt::kernels {
namespace APRT_SIMD {
// clang-format off
#include APRT_SIMD_VEC
#include "kernels/simd/vmath.inl"
#include "kernels/rowwise/f32_rowwise_impl.inl"
// clang-format on
}  // namespace APRT_SIMD

void APRT_SIMD_NAME(f32_layernorm, )(int n, const float* x, const float* g, const float* b,
                                     float eps, float* y, int r0, int r1) {
  APRT_SIMD::layernorm_rows(n, x, g, b, eps, y, r0, r1);
}
void APRT_SIMD_NAME(f32_add, )(const float* a, const float* b, float* y, size_t i0, size_t i1) {
  APRT_SIMD::add_range(a, b, y, i0, i1);
}
void APRT_SIMD_NAME(f32_softmax, )(int n, float* x, int r0, int r1) {
  APRT_SIMD::softmax_rows(n, x, r0, r1);
}
void APRT_SIMD_NAME(f32_activation, )(Act act, const float* x, float* y, size_t i0, size_t i1) {
  APRT_SIMD::activation_range(int(act), x, y, i0, i1);
}
void APRT_SIMD_NAME(f32_se_gate, )(int pixels, int c, int cr, const float* x, const float* w1,
                                   const float* b1, const float* w2t, const float* b2, float* gate,
                                   float* scratch) {
  APRT_SIMD::se_gate(pixels, c, cr, x, w1, b1, w2t, b2, gate, scratch);
}
void APRT_SIMD_NAME(f32_se_scale, )(int c, const float* x, const float* gate, float* y, int p0,
                                    int p1) {
  APRT_SIMD::se_scale(c, x, gate, y, p0, p1);
}

}  // namespace aprt::kernels
