#pragma once

#include <cstddef>

#include "kernels/common/kernel_types.h"

namespace aprt::kernels {

// Multi-head scaled dot-product attention, one query row at a time:
//   O[i, h] = sum_j softmax_j(scale * Q[i, h] . K[j, h]) V[j, h]
// Q [q_len][E], K and V [kv_len][E], O [q_len][E], E = heads * head_dim, head h
// occupies columns [h*head_dim, (h+1)*head_dim). Plain two-pass softmax over
// one row of scores: needs `scratch` of f32_attention__ref_scratch() floats.
size_t f32_attention__ref_scratch(const AttentionShape& s);
void f32_attention__ref(const AttentionShape& s, const float* q, const float* k, const float* v,
                        float scale, float* o, float* scratch);

}  // namespace aprt::kernels
