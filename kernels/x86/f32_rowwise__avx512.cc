// f32 LayerNorm, add, activations and squeeze-excite, avx512. See simd/rowwise_impl.inl.
#include <immintrin.h>

#include <cstdint>

#include "kernels/common/kernel_types.h"

namespace aprt::kernels {
namespace avx512 {
// Order matters: the vector header, then vmath, then the kernels.
// clang-format off
#include "kernels/simd/vec_avx512.h"
#include "kernels/simd/vmath.inl"
#include "kernels/simd/rowwise_impl.inl"
// clang-format on
}  // namespace avx512

void f32_layernorm__avx512(int n, const float* x, const float* g, const float* b, float eps,
                           float* y, int r0, int r1) {
  avx512::layernorm_rows(n, x, g, b, eps, y, r0, r1);
}
void f32_add__avx512(const float* a, const float* b, float* y, size_t i0, size_t i1) {
  avx512::add_range(a, b, y, i0, i1);
}
void f32_softmax__avx512(int n, float* x, int r0, int r1) {
  avx512::softmax_rows(n, x, r0, r1);
}
void f32_cross_scores__avx512(int e, int heads, const float* m, const float* pos, const float* qt,
                              float* s, size_t ls, int j0, int j1) {
  avx512::cross_scores(e, heads, m, pos, qt, s, ls, j0, j1);
}
void f32_activation__avx512(Act act, const float* x, float* y, size_t i0, size_t i1) {
  avx512::activation_range(int(act), x, y, i0, i1);
}
void f32_se_gate__avx512(int pixels, int c, int cr, const float* x, const float* w1,
                         const float* b1, const float* w2t, const float* b2, float* gate,
                         float* scratch) {
  avx512::se_gate(pixels, c, cr, x, w1, b1, w2t, b2, gate, scratch);
}
void f32_se_scale__avx512(int c, const float* x, const float* gate, float* y, int p0, int p1) {
  avx512::se_scale(c, x, gate, y, p0, p1);
}

}  // namespace aprt::kernels
