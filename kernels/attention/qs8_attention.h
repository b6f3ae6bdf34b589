// int8 attention scores (issue #4; the op's precision policy, FORMAT.md):
// Q and K are quantised dynamically — per row and head, symmetric int8 — and
// the raw score of query row i and key j is
//   s_ij = (float(sum_p q8_ip k8_jp) * sk_j) * sq_i,
// the int32 sum exact; softmax and P V stay fp32. No calibration: each row's
// scale is its own max |x| / 127, so an outlier row costs only its own
// precision. The rounding below is the one every kernel uses.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

namespace aprt::kernels {

// Scale of one row of n values: max |x| / 127 (0 for an all-zero row), and
// *inv = 127 / max |x| (0 then), the multiplier qs8_round uses. A NaN in the
// row makes the scale NaN (and an infinity infinite), so a garbage activation
// reaches the scores as NaN -- the pose check flags it -- instead of being
// quantised into a plausible value.
inline float qs8_row_scale(const float* x, int n, float* inv) {
  float amax = 0.0f;
  for (int i = 0; i < n; ++i) {
    const float a = std::fabs(x[i]);
    if (a > amax || std::isnan(a)) amax = a;
    if (std::isnan(amax)) break;
  }
  *inv = amax > 0.0f ? 127.0f / amax : 0.0f;
  return amax / 127.0f;
}

// x * inv rounded to nearest, ties to even: in [-127, 127] for |x| <= max |x|;
// 0 where x * inv is not finite (a NaN row: its scale carries the NaN).
inline int32_t qs8_round(float x, float inv) {
  const float y = x * inv;
  return std::isfinite(y) ? static_cast<int32_t>(std::nearbyint(y)) : 0;
}

// int8-score attention (AVX-512 VNNI; the int8 table's attn_* entries).
size_t qs8_attention_kq_bytes__avx512vnni(int heads, int lk_pad, int d);
void qs8_attention_pack_kv__avx512vnni(int kv_len, int lk_pad, int d, const float* k, size_t ldk,
                                       const float* v, size_t ldv, int h, uint8_t* kq, float* vp);
bool qs8_attention_8x2v__avx512vnni(int rows, int kv_len, int d, const float* q, size_t ldq,
                                    const uint8_t* kq, const float* vp, int lk_pad, float scale,
                                    float* o, size_t ldo, int h, int q0, float* scratch);
size_t qs8_attention_scratch__avx512vnni(int d);

}  // namespace aprt::kernels
