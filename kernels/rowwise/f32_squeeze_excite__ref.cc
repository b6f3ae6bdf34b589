#include "kernels/rowwise/f32_squeeze_excite__ref.h"

#include "kernels/rowwise/activation__ref.h"

namespace aprt::kernels {

size_t f32_squeeze_excite__ref_scratch(int c, int cr) {
  return size_t(c) + size_t(cr);
}

void f32_squeeze_excite__ref(int pixels, int c, int cr, const float* x, const float* w1,
                             const float* b1, const float* w2, const float* b2, float* y,
                             float* scratch) {
  float* mean = scratch;
  float* red = scratch + c;
  for (int ch = 0; ch < c; ++ch) mean[ch] = 0.0f;
  for (int p = 0; p < pixels; ++p) {
    const float* xp = x + static_cast<size_t>(p) * c;
    for (int ch = 0; ch < c; ++ch) mean[ch] += xp[ch];
  }
  const float inv = 1.0f / static_cast<float>(pixels);
  for (int ch = 0; ch < c; ++ch) mean[ch] *= inv;
  for (int r = 0; r < cr; ++r) {
    float acc = b1[r];
    for (int ch = 0; ch < c; ++ch) acc += w1[static_cast<size_t>(r) * c + ch] * mean[ch];
    red[r] = ref::apply_act(acc, Act::kSilu);
  }
  // Reuse `mean` for the per-channel gate.
  for (int ch = 0; ch < c; ++ch) {
    float acc = b2[ch];
    for (int r = 0; r < cr; ++r) acc += w2[static_cast<size_t>(ch) * cr + r] * red[r];
    mean[ch] = ref::sigmoid(acc);
  }
  for (int p = 0; p < pixels; ++p) {
    const float* xp = x + static_cast<size_t>(p) * c;
    float* yp = y + static_cast<size_t>(p) * c;
    for (int ch = 0; ch < c; ++ch) yp[ch] = xp[ch] * mean[ch];
  }
}

}  // namespace aprt::kernels
