// The single-query cross-attention's scores (CROSS_ATTENTION_1Q; reference:
// f32_cross_attention_1q__ref.h). Included inside an ISA namespace (after vmath.inl).

// Single-query attention scores over memory rows [j0, j1):
// s[h * ls + j] = qt_h . (m_j + pos_j). The key rows m_j + pos_j are formed
// in registers, four vectors of the width at a time, and dotted with up to
// eight heads' qt at once, so memory and positions are read once and the
// sum M + P is never stored (it was, and then read again by a GEMM whose
// 8-column result filled a quarter of its register tile).
static void cross_scores(int e, int heads, const float* m, const float* pos, const float* qt,
                         float* s, size_t ls, int j0, int j1) {
  constexpr int kHeads = 8, kChunk = 4;
  for (int j = j0; j < j1; ++j) {
    const float* mr = m + size_t(j) * e;
    const float* pr = pos ? pos + size_t(j) * e : nullptr;
    for (int h0 = 0; h0 < heads; h0 += kHeads) {
      const int hn = heads - h0 < kHeads ? heads - h0 : kHeads;
      V acc[kHeads];
#pragma GCC unroll 8
      for (int h = 0; h < kHeads; ++h) acc[h] = vzero();
      for (int c0 = 0; c0 < e; c0 += kChunk * kLanes) {
        V x[kChunk];
        int cnt[kChunk];
#pragma GCC unroll 4
        for (int t = 0; t < kChunk; ++t) {
          const int left = e - c0 - t * kLanes;
          cnt[t] = left < 0 ? 0 : (left > kLanes ? kLanes : left);
          const int c = c0 + t * kLanes;
          if (cnt[t] == kLanes) {
            x[t] = pr ? vadd(vload(mr + c), vload(pr + c)) : vload(mr + c);
          } else if (cnt[t] > 0) {
            x[t] = pr ? vadd(vload_n(mr + c, cnt[t]), vload_n(pr + c, cnt[t])) : vload_n(mr + c, cnt[t]);
          } else {
            x[t] = vzero();
          }
        }
#pragma GCC unroll 8
        for (int h = 0; h < kHeads; ++h) {
          if (h >= hn) break;
          const float* qh = qt + size_t(h0 + h) * e + c0;
#pragma GCC unroll 4
          for (int t = 0; t < kChunk; ++t) {
            if (cnt[t] == kLanes) {
              acc[h] = vfmadd(vload(qh + t * kLanes), x[t], acc[h]);
            } else if (cnt[t] > 0) {
              acc[h] = vfmadd(vload_n(qh + t * kLanes, cnt[t]), x[t], acc[h]);
            }
          }
        }
      }
      for (int h = 0; h < hn; ++h) s[size_t(h0 + h) * ls + j] = vreduce_add(acc[h]);
    }
  }
}
