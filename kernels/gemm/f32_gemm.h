// The fp32 GEMM family's arguments and weight packing (the LINEAR op and 1x1
// convolutions run on it; f32_gemm__ref.h is its reference).
#pragma once

#include <cstddef>

#include "kernels/common/kernel_types.h"

namespace aprt::kernels {

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
