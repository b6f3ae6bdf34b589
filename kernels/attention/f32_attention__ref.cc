#include "kernels/attention/f32_attention__ref.h"

#include <cmath>

namespace aprt::kernels {

size_t f32_attention__ref_scratch(const AttentionShape& s) {
  return size_t(s.kv_len);
}

void f32_attention__ref(const AttentionShape& s, const float* q, const float* k, const float* v,
                        float scale, float* o, float* scratch) {
  const int e = s.heads * s.head_dim;
  for (int i = 0; i < s.q_len; ++i) {
    for (int h = 0; h < s.heads; ++h) {
      const float* qi = q + static_cast<size_t>(i) * e + h * s.head_dim;
      float max = -INFINITY;
      for (int j = 0; j < s.kv_len; ++j) {
        const float* kj = k + static_cast<size_t>(j) * e + h * s.head_dim;
        float dot = 0.0f;
        for (int d = 0; d < s.head_dim; ++d) dot += qi[d] * kj[d];
        scratch[j] = dot * scale;
        if (scratch[j] > max) max = scratch[j];
      }
      double sum = 0.0;
      for (int j = 0; j < s.kv_len; ++j) {
        scratch[j] = std::exp(scratch[j] - max);
        sum += scratch[j];
      }
      const float inv = static_cast<float>(1.0 / sum);
      float* oi = o + static_cast<size_t>(i) * e + h * s.head_dim;
      for (int d = 0; d < s.head_dim; ++d) oi[d] = 0.0f;
      for (int j = 0; j < s.kv_len; ++j) {
        const float p = scratch[j] * inv;
        const float* vj = v + static_cast<size_t>(j) * e + h * s.head_dim;
        for (int d = 0; d < s.head_dim; ++d) oi[d] += p * vj[d];
      }
    }
  }
}

}  // namespace aprt::kernels
