// int8 GEMM, 4 rows x 16 columns per tile, NEON without the dot product
// (every armv8-a core): weights widened to int16, smlal by the activation
// (0..255 fits int16), and the activation quantiser shared with neondot.
// Scheme and epilogue: kernels/gemm/qs8_gemm.h.
#include <arm_neon.h>

#include "kernels/common/row_tiles.h"
#include "kernels/gemm/qs8_gemm.h"
#include "kernels/gemm/qu8s8_epilogue__neon.h"
#include "kernels/table/kernel_table.h"

namespace aprt::kernels {
namespace {

constexpr int kMr = 4, kNr = 16, kG = 1;

template <int R>
void tile(const QGemmArgs& g, int r0, int j0, int ncols, const int8_t* wp) {
  int32x4_t acc[R][4];
  for (int r = 0; r < R; ++r)
    for (int q = 0; q < 4; ++q) acc[r][q] = vdupq_n_s32(0);
  const uint8_t* a[R];
  for (int r = 0; r < R; ++r) a[r] = g.a + size_t(r0 + r) * g.lda;
  for (int p = 0; p < g.k; ++p) {
    const int8x16_t w = vld1q_s8(wp + size_t(p) * kNr);
    const int16x8_t lo = vmovl_s8(vget_low_s8(w)), hi = vmovl_s8(vget_high_s8(w));
#pragma GCC unroll 4
    for (int r = 0; r < R; ++r) {
      const int16_t av = int16_t(a[r][p]);
      acc[r][0] = vmlal_n_s16(acc[r][0], vget_low_s16(lo), av);
      acc[r][1] = vmlal_n_s16(acc[r][1], vget_high_s16(lo), av);
      acc[r][2] = vmlal_n_s16(acc[r][2], vget_low_s16(hi), av);
      acc[r][3] = vmlal_n_s16(acc[r][3], vget_high_s16(hi), av);
    }
  }
  qgemm_store_neon<R>(g, r0, j0, ncols, acc, g.a_zero);
}

void gemm(const QGemmArgs& g, int r0, int r1, int p0, int p1) {
  const size_t panel = size_t(g.k) * kNr * kG;  // bytes per packed panel
  for_panel_tiles<kMr, kNr>(g.n, r0, r1, p0, p1, [&](auto rows, int r, int j0, int ncols, int p) {
    tile<rows()>(g, r, j0, ncols, g.w_packed + size_t(p) * panel);
  });
}

}  // namespace

void u8_quantize__neon(size_t n, const float* x, float inv_scale, int32_t zero, uint8_t* q) {
  const float32x4_t s = vdupq_n_f32(inv_scale), lo = vdupq_n_f32(-512.0f), hi = vdupq_n_f32(512.0f);
  const int32x4_t z = vdupq_n_s32(zero);
  size_t i = 0;
  for (; i + 8 <= n; i += 8) {
    int32x4_t v[2];
    for (int h = 0; h < 2; ++h) {
      // maxnm: a NaN becomes lo (then 0), as in the reference.
      const float32x4_t t = vminq_f32(vmaxnmq_f32(vmulq_f32(vld1q_f32(x + i + 4 * h), s), lo), hi);
      v[h] = vaddq_s32(vcvtnq_s32_f32(t), z);  // round half to even
    }
    const uint16x8_t w16 = vcombine_u16(vqmovun_s32(v[0]), vqmovun_s32(v[1]));
    vst1_u8(q + i, vqmovn_u16(w16));
  }
  for (; i < n; ++i) {
    float t[8] = {x[i]};
    uint8_t b[8];
    u8_quantize__neon(8, t, inv_scale, zero, b);
    q[i] = b[0];
  }
}

extern const QKernelSet qs8_kernels__neon;
const QKernelSet qs8_kernels__neon = {
    .isa = "neon",
    .mr = kMr,
    .nr = kNr,
    .kgroup = kG,
    .gemm = gemm,
    .quantize = u8_quantize__neon,
    .dwconv_rows = qu8s8_dwconv2d__neon,
};

}  // namespace aprt::kernels
