#include "kernels/attention/f32_cross_attention_1q__ref.h"

#include <cmath>

namespace aprt::kernels {

size_t f32_cross_attention_1q__ref_scratch(int kv_len, int e) {
  return 2 * size_t(e) + kv_len;
}

void f32_cross_attention_1q__ref(int kv_len, int heads, int e, const float* q, const float* m,
                                 const float* pos, const float* wk, const float* wv,
                                 const float* bv, float scale, float* o, float* scratch) {
  const int d = e / heads;
  float* qt = scratch;
  float* z = scratch + e;
  float* s = scratch + 2 * e;
  for (int h = 0; h < heads; ++h) {
    for (int c = 0; c < e; ++c) {
      float acc = 0.0f;
      for (int i = 0; i < d; ++i) acc += q[h * d + i] * wk[size_t(h * d + i) * e + c];
      qt[c] = scale * acc;
    }
    float mx = -INFINITY;
    for (int j = 0; j < kv_len; ++j) {
      const float* mj = m + size_t(j) * e;
      const float* pj = pos ? pos + size_t(j) * e : nullptr;
      float acc = 0.0f;
      for (int c = 0; c < e; ++c) acc += qt[c] * (pj ? mj[c] + pj[c] : mj[c]);
      s[j] = acc;
      if (acc > mx) mx = acc;
    }
    double sum = 0.0;
    for (int j = 0; j < kv_len; ++j) {
      s[j] = std::exp(s[j] - mx);
      sum += s[j];
    }
    const float inv = static_cast<float>(1.0 / sum);
    for (int c = 0; c < e; ++c) z[c] = 0.0f;
    for (int j = 0; j < kv_len; ++j) {
      const float a = s[j] * inv;
      const float* mj = m + size_t(j) * e;
      for (int c = 0; c < e; ++c) z[c] += a * mj[c];
    }
    for (int i = 0; i < d; ++i) {
      const float* w = wv + size_t(h * d + i) * e;
      float acc = bv[h * d + i];
      for (int c = 0; c < e; ++c) acc += w[c] * z[c];
      o[h * d + i] = acc;
    }
  }
}

void f32_cross_scores__ref(int e, int heads, const float* m, const float* pos, const float* qt,
                           float* s, size_t ls, int j0, int j1) {
  for (int j = j0; j < j1; ++j) {
    const float* mr = m + size_t(j) * e;
    const float* pr = pos ? pos + size_t(j) * e : nullptr;
    for (int h = 0; h < heads; ++h) {
      const float* qh = qt + size_t(h) * e;
      float acc = 0.0f;
      for (int c = 0; c < e; ++c) acc += qh[c] * (pr ? mr[c] + pr[c] : mr[c]);
      s[size_t(h) * ls + j] = acc;
    }
  }
}

}  // namespace aprt::kernels
