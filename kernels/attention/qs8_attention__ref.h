#pragma once

#include <cstddef>

#include "kernels/common/kernel_types.h"

namespace aprt::kernels {

// y = the int8 value of x times its scale, per row and head (qs8_attention.h):
// rows x (heads * d) values at stride ld, y dense [rows][heads * d]. The fp32
// attention over fake-quantised Q and K gives the int8 scores up to the
// rounding of fp32 products of small integers (~1e-7 relative).
void qs8_fake_quantize_rows(int rows, int heads, int d, const float* x, size_t ld, float* y);

// Attention with int8 scores: Q and K fake-quantised into scratch, then
// f32_attention__ref. scratch: qs8_attention__ref_scratch() floats.
size_t qs8_attention__ref_scratch(const AttentionShape& s);
void qs8_attention__ref(const AttentionShape& s, const float* q, const float* k, const float* v,
                        float scale, float* o, float* scratch);

}  // namespace aprt::kernels
