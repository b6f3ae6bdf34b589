// int8 GEMM, 4 rows x 16 columns per tile, NEON with the dot-product
// extension (sdot: signed x signed, four products per 32-bit lane). sdot has
// no unsigned x signed form before i8mm, so activations are shifted to int8
// on the fly (a - 128, one xor) and the shift is taken out with the weights'
// column sums: sum (a - z) w = sum (a - 128) w - (z - 128) colsum.
// Compiled with +dotprod; chosen only when the CPU reports it.
#include <arm_neon.h>

#include <cstring>

#include "kernels/common/row_tiles.h"
#include "kernels/gemm/qs8_gemm.h"
#include "kernels/gemm/qu8s8_epilogue__neon.h"
#include "kernels/table/kernel_table.h"

namespace aprt::kernels {
namespace {

constexpr int kMr = 4, kNr = 16, kG = 4;

inline uint32_t load_a(const uint8_t* p, int n) {  // four bytes shifted to int8; padding 0
  uint32_t v = 0x80808080u;
  if (n >= kG) {
    std::memcpy(&v, p, 4);  // fixed size: one load
  } else {
    for (int i = 0; i < n; ++i) v = (v & ~(0xFFu << (8 * i))) | uint32_t(p[i]) << (8 * i);
  }
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
  qgemm_store_neon<R>(g, r0, j0, ncols, acc, g.a_zero - 128);
}

void gemm(const QGemmArgs& g, int r0, int r1, int p0, int p1) {
  const size_t panel = size_t((g.k + kG - 1) / kG) * kNr * kG;  // bytes per packed panel
  for_panel_tiles<kMr, kNr>(g.n, r0, r1, p0, p1, [&](auto rows, int r, int j0, int ncols, int p) {
    tile<rows()>(g, r, j0, ncols, g.w_packed + size_t(p) * panel);
  });
}

}  // namespace

void u8_quantize__neon(size_t n, const float* x, float inv_scale, int32_t zero, uint8_t* q);

extern const QKernelSet qs8_kernels__neondot;
const QKernelSet qs8_kernels__neondot = {
    .isa = "neondot",
    .mr = kMr,
    .nr = kNr,
    .kgroup = kG,
    .gemm = gemm,
    .quantize = u8_quantize__neon,
    .dwconv_rows = qu8s8_dwconv2d__neon,
};

}  // namespace aprt::kernels
