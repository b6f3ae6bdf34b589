#pragma once

#include <cstddef>

#include "kernels/common/kernel_types.h"

namespace aprt::kernels {

// y[i][p] = bf16_round(x[i][p]) (kernels/common/bf16.h): rows x n values at
// stride ld into a dense [rows][n].
void bf16_round_rows(int rows, int n, const float* x, size_t ld, float* y);

// Attention in bf16 (FORMAT.md "bf16 attention"): Q, K and V rounded to bf16,
// the scores exact products summed in fp32, the softmax in fp32, and each
// weight rounded to bf16 before it multiplies V; the row's sum is of the
// unrounded weights. The AVX-512 BF16 kernel computes the same up to the
// order of its fp32 sums and the reference exponent its weights are taken
// against (its rounded weights are relative to that reference, these to the
// row's maximum: the same relative rounding, not the same bits).
// scratch: bf16_attention__ref_scratch() floats.
size_t bf16_attention__ref_scratch(const AttentionShape& s);
void bf16_attention__ref(const AttentionShape& s, const float* q, const float* k, const float* v,
                         float scale, float* o, float* scratch);

}  // namespace aprt::kernels
