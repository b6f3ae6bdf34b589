// int8 kernels (issue #4), one table per ISA, chosen once like KernelSet.
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

// int8 depthwise convolution: X uint8 NHWC (per-tensor zero point), W int8
// [KH][KW][C] per-channel symmetric, given to the fast kernels as floats
// (exact; packed once at load), y = act(mult[c] * acc + bias[c]).
struct QDwConvArgs {
  Conv2dShape shape;
  const uint8_t* x;
  int32_t a_zero;
  const float* w;  // [KH][KW][C], the int8 values as floats
  const float* mult;
  const float* bias;
  Act act;  // any: applied in fp32 after the epilogue
  float* y;
};
// The fast depthwise kernels accumulate in float, exact while the window has
// at most this many taps (255 * 127 * taps < 2^24).
inline constexpr int kMaxQDwTaps = 256;

struct QKernelSet {
  const char* isa;  // "avx512vnni", "avx2", "neondot", "neon"
  int mr, nr, kgroup;
  // C rows [r0, r1) x column panels [p0, p1) (panels of nr columns).
  void (*gemm)(const QGemmArgs& g, int r0, int r1, int p0, int p1);
  // q[i] = clamp(round_half_even(x[i] * inv_scale) + zero, 0, 255).
  void (*quantize)(size_t n, const float* x, float inv_scale, int32_t zero, uint8_t* q);
  // Output rows [oy0, oy1) of an int8 depthwise convolution.
  void (*dwconv_rows)(const QDwConvArgs& a, int oy0, int oy1);
  // Attention with int8 scores (kernels/common/qs8_attention.h), null where
  // this table has none (the op then fake-quantises Q and K and runs the fp32
  // kernel). Like KernelSet's attention: the most query rows per call, the
  // row-group size, keys per block; the packed K of all heads (attn_kq_bytes)
  // and V (fp32, E * lk_pad floats); per-thread scratch floats.
  int attn_max_rows, attn_group_rows, attn_key_block;
  size_t (*attn_kq_bytes)(int heads, int lk_pad, int d);
  void (*attn_pack_kv)(int kv_len, int lk_pad, int d, const float* k, size_t ldk, const float* v,
                       size_t ldv, int h, uint8_t* kq, float* vp);
  bool (*attn_block)(int rows, int kv_len, int d, const float* q, size_t ldq, const uint8_t* kq,
                     const float* vp, int lk_pad, float scale, float* o, size_t ldo, int h, int q0,
                     float* scratch);
  size_t (*attn_scratch)(int d);
};

void qu8s8_dwconv__avx512(const QDwConvArgs& a, int oy0, int oy1);
void qu8s8_dwconv__avx2(const QDwConvArgs& a, int oy0, int oy1);
void qu8s8_dwconv__neon(const QDwConvArgs& a, int oy0, int oy1);

// int8-score attention (AVX-512 VNNI; QKernelSet::attn_*).
size_t qs8_attention_kq_bytes__avx512vnni(int heads, int lk_pad, int d);
void qs8_attention_pack_kv__avx512vnni(int kv_len, int lk_pad, int d, const float* k, size_t ldk,
                                       const float* v, size_t ldv, int h, uint8_t* kq, float* vp);
bool qs8_attention_8x2v__avx512vnni(int rows, int kv_len, int d, const float* q, size_t ldq,
                                    const uint8_t* kq, const float* vp, int lk_pad, float scale,
                                    float* o, size_t ldo, int h, int q0, float* scratch);
size_t qs8_attention_scratch__avx512vnni(int d);

// Packs W [n][k] int8 (row-major, as LINEAR stores it) into panels of nr
// columns with k in groups of kgroup (zero-padded in both):
// out[((panel * kg + g) * nr + jj) * kgroup + kk] = W[panel * nr + jj][g * kgroup + kk].
size_t qs8_pack_w_bytes(int n, int k, int nr, int kgroup);
void qs8_pack_w(int n, int k, int nr, int kgroup, const int8_t* w, int8_t* out);
// colsum[j] = sum_p W[j][p].
void qs8_column_sums(int n, int k, const int8_t* w, int32_t* colsum);

// The tables this build contains (null where not compiled in).
const QKernelSet* qkernel_set_avx512vnni();
const QKernelSet* qkernel_set_avx2();
const QKernelSet* qkernel_set_neondot();
const QKernelSet* qkernel_set_neon();
// The best table this CPU runs, or null (the reference kernels then).
const QKernelSet* qkernel_set_best();

}  // namespace aprt::kernels
