// f32 LayerNorm, add, activations and squeeze-excite, avx2. See simd/rowwise_impl.inl.
#include <immintrin.h>

#include <cstdint>

#include "kernels/common/kernel_types.h"

namespace aprt::kernels {
namespace avx2 {
// Order matters: the vector header, then vmath, then the kernels.
// clang-format off
#include "kernels/simd/vec_avx2.h"
#include "kernels/simd/vmath.inl"
#include "kernels/simd/rowwise_impl.inl"
// clang-format on
}  // namespace avx2

void f32_layernorm__avx2(int n, const float* x, const float* g, const float* b, float eps, float* y,
                         int r0, int r1) {
  avx2::layernorm_rows(n, x, g, b, eps, y, r0, r1);
}
void f32_add__avx2(const float* a, const float* b, float* y, size_t i0, size_t i1) {
  avx2::add_range(a, b, y, i0, i1);
}
void f32_softmax__avx2(int n, float* x, int r0, int r1) {
  avx2::softmax_rows(n, x, r0, r1);
}
void f32_cross_scores__avx2(int e, int heads, const float* m, const float* pos, const float* qt,
                            float* s, size_t ls, int j0, int j1) {
  avx2::cross_scores(e, heads, m, pos, qt, s, ls, j0, j1);
}
void f32_activation__avx2(Act act, const float* x, float* y, size_t i0, size_t i1) {
  avx2::activation_range(int(act), x, y, i0, i1);
}
void f32_se_gate__avx2(int pixels, int c, int cr, const float* x, const float* w1, const float* b1,
                       const float* w2t, const float* b2, float* gate, float* scratch) {
  avx2::se_gate(pixels, c, cr, x, w1, b1, w2t, b2, gate, scratch);
}
void f32_se_scale__avx2(int c, const float* x, const float* gate, float* y, int p0, int p1) {
  avx2::se_scale(c, x, gate, y, p0, p1);
}

}  // namespace aprt::kernels
