// Parameter blocks shared by reference and optimised kernels.
//
// Kernels know shapes and pointers, nothing about model files or the engine
// (DESIGN.md section 3: kernels/ use nothing of ours). Layouts: feature maps
// NHWC with batch 1 ([H][W][C]); matrices row-major.
#pragma once

#include <cstddef>
#include <cstdint>

namespace aprt::kernels {

// Same numbering as model_bin's activation codes.
enum class Act : int32_t { kNone = 0, kSilu = 1, kGelu = 2, kSigmoid = 3, kRelu = 4 };

struct Conv2dShape {
  int in_h, in_w, in_c;
  int out_h, out_w, out_c;
  int kernel_h, kernel_w;
  int stride_h, stride_w;
  int pad_top, pad_left;  // bottom/right padding is implied by the output size
};

// Weight layouts: dense [out_c][kernel_h][kernel_w][in_c]; depthwise [kernel_h][kernel_w][c]
// (in_c == out_c == c).

struct GemmShape {
  int m, n, k;  // Y[m][n] = X[m][k] * W[n][k]^T
};

struct AttentionShape {
  int q_len, kv_len, heads, head_dim;  // Q [q_len][heads*head_dim], K/V [kv_len][heads*head_dim]
};

// C[m][n] = act(A[m][k] B[k][n] + bias[n]) + residual[m][n], for the optimised GEMMs.
// B is read in column panels of the kernel's NR columns: panel j starts at
// b + j * b_panel_stride and its rows are ldb floats apart. Weights are packed
// at load (f32_pack_b: ldb = NR, b_panel_stride = k * NR, zero-padded); a
// row-major activation matrix [k][n] is used as is (ldb = n, b_panel_stride =
// NR, b_padded = false: the last panel is read with masked loads).
struct GemmArgs {
  int m, n, k;
  const float* a;
  size_t lda;
  const float* b;
  size_t ldb;
  size_t b_panel_stride;
  bool b_padded;
  const float* bias;      // [n] or null
  const float* residual;  // or null
  size_t ldr;
  float* c;
  size_t ldc;
  Act act;
};

// Packs W [n][k] (row-major, as LINEAR stores it) into zero-padded panels of nr
// columns: out[(j * k + p) * nr + jj] = W[j * nr + jj][p].
size_t f32_pack_b_floats(int n, int k, int nr);
void f32_pack_b(int n, int k, int nr, const float* w, float* out);

}  // namespace aprt::kernels
