// f32 fused multi-head attention (online softmax), query chunks of
// kAttnChunk rows in groups of 8 query rows per block, avx512.
// See simd/attention_impl.inl.
#include <immintrin.h>

#include <cstdint>

#include "kernels/common/kernel_types.h"

namespace aprt::kernels {
namespace avx512 {
// Order matters: the vector header, then vmath, then the kernels.
// clang-format off
#include "kernels/simd/vec_avx512.h"
#include "kernels/simd/vmath.inl"
#include "kernels/simd/attention_impl.inl"
// clang-format on
}  // namespace avx512

void f32_attention_pack_kv__avx512(int kv_len, int lk_pad, int d, const float* k, size_t ldk,
                                   const float* v, size_t ldv, int h, float* kt, float* vp) {
  avx512::attn_pack_kv(kv_len, lk_pad, d, k, ldk, v, ldv, h, kt, vp);
}
bool f32_attention_8x2v__avx512(int rows, int kv_len, int d, const float* q, size_t ldq,
                                const float* kt, const float* vp, int lk_pad, float scale, float* o,
                                size_t ldo, int h, int q0, float* scratch) {
  return avx512::attn_block<8, 2>(rows, kv_len, d, q, ldq, kt, vp, lk_pad, scale, o, ldo, h, q0,
                                  scratch);
}
size_t f32_attention_scratch__avx512(int d) {
  return avx512::attn_thread_scratch(8, (d + avx512::kLanes - 1) / avx512::kLanes);
}

}  // namespace aprt::kernels
