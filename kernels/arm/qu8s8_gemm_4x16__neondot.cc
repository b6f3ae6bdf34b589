// int8 GEMM, 4 rows x 16 columns per tile, NEON with the dot-product
// extension (sdot: signed x signed, four products per 32-bit lane). sdot has
// no unsigned x signed form before i8mm, so activations are shifted to int8
// on the fly (a - 128, one xor) and the shift is taken out with the weights'
// column sums: sum (a - z) w = sum (a - 128) w - (z - 128) colsum.
// Compiled with +dotprod; chosen only when the CPU reports it.
#include <arm_neon.h>

#include <cstring>

#include "kernels/common/qkernel_set.h"

namespace aprt::kernels {
namespace {

constexpr int kMr = 4, kNr = 16, kG = 4;

inline uint32_t load_a(const uint8_t* p, int n) {  // four bytes shifted to int8; padding 0
  uint32_t v = 0x80808080u;
  std::memcpy(&v, p, size_t(n < kG ? n : kG));
  return v ^ 0x80808080u;
}

template <int R>
void tile(const QGemmArgs& g, int r0, int j0, int ncols, const int8_t* wp) {
  int32x4_t acc[R][4];
  for (int r = 0; r < R; ++r)
    for (int q = 0; q < 4; ++q) acc[r][q] = vdupq_n_s32(0);
  const uint8_t* a[R];
  for (int r = 0; r < R; ++r) a[r] = g.a + size_t(r0 + r) * g.lda;
  const int groups = (g.k + kG - 1) / kG;
  for (int gi = 0; gi < groups; ++gi) {
    const int8_t* w = wp + size_t(gi) * kNr * kG;
    const int8x16_t b0 = vld1q_s8(w), b1 = vld1q_s8(w + 16), b2 = vld1q_s8(w + 32),
                    b3 = vld1q_s8(w + 48);
    const int left = g.k - gi * kG;
#pragma GCC unroll 4
    for (int r = 0; r < R; ++r) {
      const int8x16_t av = vreinterpretq_s8_u32(vdupq_n_u32(load_a(a[r] + gi * kG, left)));
      acc[r][0] = vdotq_s32(acc[r][0], b0, av);
      acc[r][1] = vdotq_s32(acc[r][1], b1, av);
      acc[r][2] = vdotq_s32(acc[r][2], b2, av);
      acc[r][3] = vdotq_s32(acc[r][3], b3, av);
    }
  }
  const int32_t shift = g.a_zero - 128;
  for (int q = 0; q < 4; ++q) {
    const int cols = ncols - 4 * q;
    if (cols <= 0) break;
    const int j = j0 + 4 * q;
    int32_t cs[4] = {};
    float mu[4] = {}, bi[4] = {};
    for (int t = 0; t < cols && t < 4; ++t) {
      cs[t] = g.w_colsum[j + t];
      mu[t] = g.mult[j + t];
      bi[t] = g.bias ? g.bias[j + t] : 0.0f;
    }
    const int32x4_t corr = vmulq_n_s32(vld1q_s32(cs), shift);
    const float32x4_t mult = vld1q_f32(mu), bias = vld1q_f32(bi);
    for (int r = 0; r < R; ++r) {
      const int32x4_t exact = vsubq_s32(acc[r][q], corr);
      float32x4_t y = vfmaq_f32(bias, vcvtq_f32_s32(exact), mult);
      float out[4];
      vst1q_f32(out, y);
      const float* res = g.residual ? g.residual + size_t(r0 + r) * g.ldr + j : nullptr;
      float* c = g.c + size_t(r0 + r) * g.ldc + j;
      for (int t = 0; t < cols && t < 4; ++t) {
        float v = out[t];
        if (res) v += res[t];
        if (g.act == Act::kRelu) v = v > 0.0f ? v : 0.0f;
        c[t] = v;
      }
    }
  }
}

void gemm(const QGemmArgs& g, int r0, int r1, int p0, int p1) {
  const int groups = (g.k + kG - 1) / kG;
  for (int p = p0; p < p1; ++p) {
    const int j0 = p * kNr, ncols = g.n - j0 < kNr ? g.n - j0 : kNr;
    const int8_t* wp = g.w_packed + size_t(p) * groups * kNr * kG;
    int r = r0;
    for (; r + kMr <= r1; r += kMr) tile<kMr>(g, r, j0, ncols, wp);
    switch (r1 - r) {
      case 3: tile<3>(g, r, j0, ncols, wp); break;
      case 2: tile<2>(g, r, j0, ncols, wp); break;
      case 1: tile<1>(g, r, j0, ncols, wp); break;
      default: break;
    }
  }
}

}  // namespace

void u8_quantize__neon(size_t n, const float* x, float inv_scale, int32_t zero, uint8_t* q);

namespace {
const QKernelSet kSet = {"neondot", kMr, kNr, kG, gemm, u8_quantize__neon};
}  // namespace

const QKernelSet* qkernel_set_neondot() {
  return &kSet;
}

}  // namespace aprt::kernels
