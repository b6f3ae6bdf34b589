#include "kernels/attention/bf16_attention__ref.h"

#include <cmath>

#include "kernels/common/bf16.h"

namespace aprt::kernels {

void bf16_round_rows(int rows, int n, const float* x, size_t ld, float* y) {
  for (int i = 0; i < rows; ++i) {
    for (int p = 0; p < n; ++p) y[size_t(i) * n + p] = bf16_round(x[size_t(i) * ld + p]);
  }
}

size_t bf16_attention__ref_scratch(const AttentionShape& s) {
  const size_t e = size_t(s.heads) * s.head_dim;
  return (size_t(s.q_len) + 2 * size_t(s.kv_len)) * e + size_t(s.kv_len);
}

void bf16_attention__ref(const AttentionShape& s, const float* q, const float* k, const float* v,
                         float scale, float* o, float* scratch) {
  const int e = s.heads * s.head_dim;
  float* qb = scratch;
  float* kb = qb + size_t(s.q_len) * e;
  float* vb = kb + size_t(s.kv_len) * e;
  float* w = vb + size_t(s.kv_len) * e;
  bf16_round_rows(s.q_len, e, q, size_t(e), qb);
  bf16_round_rows(s.kv_len, e, k, size_t(e), kb);
  bf16_round_rows(s.kv_len, e, v, size_t(e), vb);
  for (int i = 0; i < s.q_len; ++i) {
    for (int h = 0; h < s.heads; ++h) {
      const float* qi = qb + size_t(i) * e + size_t(h) * s.head_dim;
      float max = -INFINITY;
      for (int j = 0; j < s.kv_len; ++j) {
        const float* kj = kb + size_t(j) * e + size_t(h) * s.head_dim;
        float dot = 0.0f;
        for (int d = 0; d < s.head_dim; ++d) dot = std::fma(qi[d], kj[d], dot);  // exact products
        w[j] = dot * scale;
        if (w[j] > max || std::isnan(w[j])) max = w[j];
      }
      double sum = 0.0;
      for (int j = 0; j < s.kv_len; ++j) {
        w[j] = std::exp(w[j] - max);
        sum += w[j];
      }
      const float inv = static_cast<float>(1.0 / sum);
      float* oi = o + size_t(i) * e + size_t(h) * s.head_dim;
      for (int d = 0; d < s.head_dim; ++d) oi[d] = 0.0f;
      for (int j = 0; j < s.kv_len; ++j) {
        const float p = bf16_round(w[j]);
        const float* vj = vb + size_t(j) * e + size_t(h) * s.head_dim;
        for (int d = 0; d < s.head_dim; ++d) oi[d] = std::fma(p, vj[d], oi[d]);
      }
      for (int d = 0; d < s.head_dim; ++d) oi[d] *= inv;
    }
  }
}

}  // namespace aprt::kernels
