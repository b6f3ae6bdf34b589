// The int8 GEMM family (issue #4): arguments and weight packing. Its kernels
// are the int8 part of the kernel table (kernels/table/kernel_table.h).
//
// Quantisation scheme (the one the converter's calibration will write):
//   activations  uint8, per tensor, asymmetric: real = a_scale * (q - a_zero)
//   weights      int8, per output channel, symmetric: real = w_scale[j] * q, q in [-127, 127]
//   accumulation int32, exact: acc[m][j] = sum_p (a[m][p] - a_zero) * w[j][p]
//   epilogue     y = act(mult[j] * float(acc) + bias[j] (+ residual)), mult[j] = a_scale *
//   w_scale[j],
//                one fused multiply-add, so every ISA and the reference give the same bits
//                (act: none or ReLU fused; others run as the fp32 activation kernel after).
// Each kernel computes the same int32 accumulator by its own instructions:
// AVX-512 VNNI vpdpbusd (u8 x s8, 4 per lane), AVX2 vpmaddwd on widened
// int16 pairs, NEON dotprod sdot on activations shifted to int8 (a - 128,
// corrected with the weights' column sums), NEON smlal on widened int16.
#pragma once

#include <cstddef>
#include <cstdint>

#include "kernels/common/kernel_types.h"

namespace aprt::kernels {

struct QGemmArgs {
  int m, n, k;
  const uint8_t* a;  // [m][lda], k valid bytes per row
  size_t lda;
  int32_t a_zero;           // 0..255
  const int8_t* w_packed;   // qs8_pack_w(n, k, nr, kgroup) for this table
  const int32_t* w_colsum;  // [n]: sum_p w[j][p]
  const float* mult;        // [n]: a_scale * w_scale[j]
  const float* bias;        // [n] or null
  const float* residual;    // [m][ldr] or null
  size_t ldr;
  float* c;
  size_t ldc;
  Act act;  // kNone or kRelu
};

// Packs W [n][k] int8 (row-major, as LINEAR stores it) into panels of nr
// columns with k in groups of kgroup (zero-padded in both):
// out[((panel * kg + g) * nr + jj) * kgroup + kk] = W[panel * nr + jj][g * kgroup + kk].
size_t qs8_pack_w_bytes(int n, int k, int nr, int kgroup);
void qs8_pack_w(int n, int k, int nr, int kgroup, const int8_t* w, int8_t* out);
// colsum[j] = sum_p W[j][p].
void qs8_column_sums(int n, int k, const int8_t* w, int32_t* colsum);

}  // namespace aprt::kernels
