// One ISA's fast kernels, as a table of function pointers. The engine picks
// one table at load() from what the CPU reports (runtime/engine/kernel_select.cc)
// and ops store the functions they need; nothing on the run path asks about the
// CPU again. Every function has a reference twin in kernels/ref/ and a
// randomised differential test (tests/kernels/fast_kernels_test.cc).
#pragma once

#include <cstddef>

#include "kernels/common/kernel_types.h"
#include "kernels/common/preprocess_image.h"

namespace aprt::kernels {

struct KernelSet {
  const char* isa;  // "avx512", "avx2", "neon", ...
  int lanes;        // floats per vector register
  int gemm_mr;      // rows per GEMM tile
  int gemm_nr;      // columns per packed weight panel (f32_pack_b's nr)
  // C rows [r0, r1) x column panels [p0, p1) of a GemmArgs product.
  void (*gemm)(const GemmArgs& g, int r0, int r1, int p0, int p1);
  // Output rows [oy0, oy1) of a depthwise convolution (weights [KH][KW][C]).
  void (*dwconv_rows)(const Conv2dShape& s, const float* x, const float* w, const float* bias,
                      Act act, float* y, int oy0, int oy1);
  // Output rows [oy0, oy1) of a dense convolution; weights packed by
  // f32_conv2d_pack_weights ([KH][KW][Ci][Co]).
  void (*conv_rows)(const Conv2dShape& s, const float* x, const float* w_packed, const float* bias,
                    const float* residual, Act act, float* y, int oy0, int oy1);
  void (*layernorm_rows)(int n, const float* x, const float* gamma, const float* beta, float eps,
                         float* y, int r0, int r1);
  void (*add)(const float* a, const float* b, float* y, size_t i0, size_t i1);
  // In-place softmax of rows [r0, r1) of an [rows][n] matrix.
  void (*softmax_rows)(int n, float* x, int r0, int r1);
  // Single-query attention scores s[h * ls + j] = qt_h . (m_j + pos_j) of
  // memory rows [j0, j1) (pos may be null; kernels/ref/f32_cross_attention_1q__ref.h).
  void (*cross_scores)(int e, int heads, const float* m, const float* pos, const float* qt,
                       float* s, size_t ls, int j0, int j1);
  void (*activation)(Act act, const float* x, float* y, size_t i0, size_t i1);
  // Squeeze-excite: the per-channel gate (W2 transposed: [Cr][C]); scratch C + Cr floats.
  void (*se_gate)(int pixels, int c, int cr, const float* x, const float* w1, const float* b1,
                  const float* w2t, const float* b2, float* gate, float* scratch);
  void (*se_scale)(int c, const float* x, const float* gate, float* y, int p0, int p1);
  // Attention: the most query rows one attn_block call takes, its row-group
  // size, and keys per block (K and V are packed padded to a multiple of it:
  // lk_pad floats per head dimension).
  int attn_max_rows;
  int attn_group_rows;
  int attn_key_block;
  // Packs head h of K and V ([L][E] rows) into kt and vp (E * lk_pad floats each).
  void (*attn_pack_kv)(int kv_len, int lk_pad, int d, const float* k, size_t ldk, const float* v,
                       size_t ldv, int h, float* kt, float* vp);
  // false: head width unsupported here (use the reference kernel).
  bool (*attn_block)(int rows, int kv_len, int d, const float* q, size_t ldq, const float* kt,
                     const float* vp, int lk_pad, float scale, float* o, size_t ldo, int h, int q0,
                     float* scratch);
  size_t (*attn_scratch)(int d);  // per-thread floats for attn_block
  // A camera frame to the network input (kernels/common/preprocess_image.h).
  void (*preprocess)(const PreprocessPlan& plan, const ImageView& img, float* out);
};

// Dense convolution weights [Co][KH][KW][Ci] -> [KH][KW][Ci][Co].
void f32_conv2d_pack_weights(int co, int kh, int kw, int ci, const float* w, float* out);

// Tables of the ISAs this build contains (null where not compiled in).
const KernelSet* kernel_set_avx512();
const KernelSet* kernel_set_avx2();
const KernelSet* kernel_set_neon();

}  // namespace aprt::kernels
