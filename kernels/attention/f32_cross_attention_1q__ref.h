#pragma once

#include <cstddef>

namespace aprt::kernels {

// Multi-head attention of ONE query over kv_len memory rows whose keys and
// values would be projections of the memory, computed without projecting it:
//   qt_h   = scale * W_k,h^T q_h                         (E values per head)
//   a_h    = softmax_j(qt_h . (m_j + pos_j))             (the key bias cancels)
//   o_h    = W_v,h (sum_j a_h,j m_j) + b_v,h             (the weights sum to 1)
// q [E] is the projected query (bias included), m and pos [kv_len][E] (pos may
// be null), wk and wv [E][E] as LINEAR stores them, o [E]. scratch: 2E + kv_len.
size_t f32_cross_attention_1q__ref_scratch(int kv_len, int e);
void f32_cross_attention_1q__ref(int kv_len, int heads, int e, const float* q, const float* m,
                                 const float* pos, const float* wk, const float* wv,
                                 const float* bv, float scale, float* o, float* scratch);

// The scores of the single-query attention, for memory rows [j0, j1):
//   s[h * ls + j] = qt_h . (m_j + pos_j)      (pos may be null)
// qt [heads][E], m and pos [rows][E]. The fast kernels' twin (KernelSet::cross_scores).
void f32_cross_scores__ref(int e, int heads, const float* m, const float* pos, const float* qt,
                           float* s, size_t ls, int j0, int j1);

}  // namespace aprt::kernels
