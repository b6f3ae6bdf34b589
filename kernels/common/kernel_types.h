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

}  // namespace aprt::kernels
