// f32 LayerNorm, add, activations and squeeze-excite, neon. See simd/rowwise_impl.inl.
#include <arm_neon.h>

#include <cstdint>

#include "kernels/common/kernel_types.h"

namespace aprt::kernels {
namespace neon {
// Order matters: the vector header, then vmath, then the kernels.
// clang-format off
#include "kernels/simd/vec_neon.h"
#include "kernels/simd/vmath.inl"
#include "kernels/simd/rowwise_impl.inl"
// clang-format on
}  // namespace neon

void f32_layernorm__neon(int n, const float* x, const float* g, const float* b, float eps, float* y,
                         int r0, int r1) {
  neon::layernorm_rows(n, x, g, b, eps, y, r0, r1);
}
void f32_add__neon(const float* a, const float* b, float* y, size_t i0, size_t i1) {
  neon::add_range(a, b, y, i0, i1);
}
void f32_softmax__neon(int n, float* x, int r0, int r1) {
  neon::softmax_rows(n, x, r0, r1);
}
void f32_cross_scores__neon(int e, int heads, const float* m, const float* pos, const float* qt,
                            float* s, size_t ls, int j0, int j1) {
  neon::cross_scores(e, heads, m, pos, qt, s, ls, j0, j1);
}
void f32_activation__neon(Act act, const float* x, float* y, size_t i0, size_t i1) {
  neon::activation_range(int(act), x, y, i0, i1);
}
void f32_se_gate__neon(int pixels, int c, int cr, const float* x, const float* w1, const float* b1,
                       const float* w2t, const float* b2, float* gate, float* scratch) {
  neon::se_gate(pixels, c, cr, x, w1, b1, w2t, b2, gate, scratch);
}
void f32_se_scale__neon(int c, const float* x, const float* gate, float* y, int p0, int p1) {
  neon::se_scale(c, x, gate, y, p0, p1);
}

}  // namespace aprt::kernels
