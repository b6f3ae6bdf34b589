#include "kernels/attention/qs8_attention__ref.h"

#include "kernels/attention/f32_attention__ref.h"
#include "kernels/attention/qs8_attention.h"

namespace aprt::kernels {

void qs8_fake_quantize_rows(int rows, int heads, int d, const float* x, size_t ld, float* y) {
  const size_t e = size_t(heads) * d;
  for (int i = 0; i < rows; ++i) {
    for (int h = 0; h < heads; ++h) {
      const float* xr = x + size_t(i) * ld + size_t(h) * d;
      float* yr = y + size_t(i) * e + size_t(h) * d;
      float inv = 0.0f;
      const float scale = qs8_row_scale(xr, d, &inv);
      for (int p = 0; p < d; ++p) yr[p] = float(qs8_round(xr[p], inv)) * scale;
    }
  }
}

size_t qs8_attention__ref_scratch(const AttentionShape& s) {
  const size_t e = size_t(s.heads) * s.head_dim;
  return (size_t(s.q_len) + s.kv_len) * e + f32_attention__ref_scratch(s);
}

void qs8_attention__ref(const AttentionShape& s, const float* q, const float* k, const float* v,
                        float scale, float* o, float* scratch) {
  const size_t e = size_t(s.heads) * s.head_dim;
  float* qf = scratch;
  float* kf = qf + size_t(s.q_len) * e;
  qs8_fake_quantize_rows(s.q_len, s.heads, s.head_dim, q, e, qf);
  qs8_fake_quantize_rows(s.kv_len, s.heads, s.head_dim, k, e, kf);
  f32_attention__ref(s, qf, kf, v, scale, o, kf + size_t(s.kv_len) * e);
}

}  // namespace aprt::kernels
