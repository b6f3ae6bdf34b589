// f32 fused multi-head attention (online softmax), query chunks of
// kAttnChunk rows in groups of 8 query rows per block, neon.
// See simd/attention_impl.inl.
#include <arm_neon.h>

#include <cstdint>

#include "kernels/common/kernel_types.h"

namespace aprt::kernels {
namespace neon {
// Order matters: the vector header, then vmath, then the kernels.
// clang-format off
#include "kernels/simd/vec_neon.h"
#include "kernels/simd/vmath.inl"
#include "kernels/simd/attention_impl.inl"
// clang-format on
}  // namespace neon

void f32_attention_pack_kv__neon(int kv_len, int lk_pad, int d, const float* k, size_t ldk,
                                 const float* v, size_t ldv, int h, float* kt, float* vp) {
  neon::attn_pack_kv(kv_len, lk_pad, d, k, ldk, v, ldv, h, kt, vp);
}
bool f32_attention_3x4v__neon(int rows, int kv_len, int d, const float* q, size_t ldq,
                              const float* kt, const float* vp, int lk_pad, float scale, float* o,
                              size_t ldo, int h, int q0, float* scratch) {
  return neon::attn_block<3, 4>(rows, kv_len, d, q, ldq, kt, vp, lk_pad, scale, o, ldo, h, q0,
                                scratch);
}
size_t f32_attention_scratch__neon(int d) {
  return neon::attn_thread_scratch(3, (d + neon::kLanes - 1) / neon::kLanes);
}

}  // namespace aprt::kernels
