// Register-blocked GEMM on top of vec_*.h: an R x (NV * kLanes) tile per call,
// B rows loaded as NV vectors, A elements broadcast, accumulation in registers,
// epilogue (bias, activation, residual) fused. Included inside an ISA namespace.

template <int R, int NV, bool kFull>
static inline void gemm_tile(int k, const float* a, size_t lda, const float* b, size_t ldb,
                             int nvalid, bool b_padded, const float* bias, const float* res,
                             size_t ldr, float* c, size_t ldc, int act) {
  V acc[R][NV];
  int cnt[NV];
#pragma GCC unroll 8
  for (int j = 0; j < NV; ++j) {
    const int left = nvalid - j * kLanes;
    cnt[j] = left < 0 ? 0 : (left > kLanes ? kLanes : left);
  }
#pragma GCC unroll 8
  for (int j = 0; j < NV; ++j) {
    V init = vzero();
    if (bias) init = kFull ? vload(bias + j * kLanes) : vload_n(bias + j * kLanes, cnt[j]);
#pragma GCC unroll 16
    for (int r = 0; r < R; ++r) acc[r][j] = init;
  }
  if (kFull || b_padded) {
#pragma GCC unroll 4
    for (int p = 0; p < k; ++p) {
      V bv[NV];
#pragma GCC unroll 8
      for (int j = 0; j < NV; ++j) bv[j] = vload(b + size_t(p) * ldb + j * kLanes);
#pragma GCC unroll 16
      for (int r = 0; r < R; ++r) {
        const V av = vset1(a[size_t(r) * lda + p]);
#pragma GCC unroll 8
        for (int j = 0; j < NV; ++j) acc[r][j] = vfmadd(av, bv[j], acc[r][j]);
      }
    }
  } else {
    for (int p = 0; p < k; ++p) {
      V bv[NV];
#pragma GCC unroll 8
      for (int j = 0; j < NV; ++j) bv[j] = vload_n(b + size_t(p) * ldb + j * kLanes, cnt[j]);
#pragma GCC unroll 16
      for (int r = 0; r < R; ++r) {
        const V av = vset1(a[size_t(r) * lda + p]);
#pragma GCC unroll 8
        for (int j = 0; j < NV; ++j) acc[r][j] = vfmadd(av, bv[j], acc[r][j]);
      }
    }
  }
#pragma GCC unroll 16
  for (int r = 0; r < R; ++r) {
#pragma GCC unroll 8
    for (int j = 0; j < NV; ++j) {
      V v = act ? vact(acc[r][j], act) : acc[r][j];
      float* out = c + size_t(r) * ldc + j * kLanes;
      if (kFull) {
        if (res) v = vadd(v, vload(res + size_t(r) * ldr + j * kLanes));
        vstore(out, v);
      } else {
        if (res) v = vadd(v, vload_n(res + size_t(r) * ldr + j * kLanes, cnt[j]));
        vstore_n(out, v, cnt[j]);
      }
    }
  }
}

template <int R, int NV>
static inline void gemm_tile_any(const GemmArgs& g, int row, int panel) {
  constexpr int kNR = NV * kLanes;
  const int col = panel * kNR;
  const int nvalid = g.n - col < kNR ? g.n - col : kNR;
  const float* a = g.a + size_t(row) * g.lda;
  const float* b = g.b + size_t(panel) * g.b_panel_stride;
  const float* bias = g.bias ? g.bias + col : nullptr;
  const float* res = g.residual ? g.residual + size_t(row) * g.ldr + col : nullptr;
  float* c = g.c + size_t(row) * g.ldc + col;
  const int act = static_cast<int>(g.act);
  if constexpr (NV > 1) {
    // A last panel of at most one vector's columns (EfficientNet's 16-, 40-,
    // 80-, 112-, 144- and 240-channel 1x1 convolutions): one vector wide, not
    // NV with the rest multiplying the panel's zero padding.
    if (nvalid <= kLanes && g.b_padded) {
      if (nvalid == kLanes) {
        gemm_tile<R, 1, true>(g.k, a, g.lda, b, g.ldb, nvalid, true, bias, res, g.ldr, c, g.ldc,
                              act);
      } else {
        gemm_tile<R, 1, false>(g.k, a, g.lda, b, g.ldb, nvalid, true, bias, res, g.ldr, c, g.ldc,
                               act);
      }
      return;
    }
  }
  if (nvalid == kNR) {
    gemm_tile<R, NV, true>(g.k, a, g.lda, b, g.ldb, nvalid, g.b_padded, bias, res, g.ldr, c, g.ldc,
                           act);
  } else {
    gemm_tile<R, NV, false>(g.k, a, g.lda, b, g.ldb, nvalid, g.b_padded, bias, res, g.ldr, c,
                            g.ldc, act);
  }
}

// Rows [row_begin, row_end) x panels [panel_begin, panel_end) of C. Row tiles
// outside, panels inside: the tile's A rows stay in L1 while B panels stream.
template <int MR, int NV>
static void gemm_range(const GemmArgs& g, int row_begin, int row_end, int panel_begin,
                       int panel_end) {
  int i = row_begin;
  for (; i + MR <= row_end; i += MR) {
    for (int pj = panel_begin; pj < panel_end; ++pj) gemm_tile_any<MR, NV>(g, i, pj);
  }
  const int left = row_end - i;
  if (left <= 0) return;
  for (int pj = panel_begin; pj < panel_end; ++pj) {
    // Remaining rows: one call with the exact row count.
    switch (left) {
      case 1: gemm_tile_any<1, NV>(g, i, pj); break;
      case 2: if constexpr (MR > 2) gemm_tile_any<2, NV>(g, i, pj); break;
      case 3: if constexpr (MR > 3) gemm_tile_any<3, NV>(g, i, pj); break;
      case 4: if constexpr (MR > 4) gemm_tile_any<4, NV>(g, i, pj); break;
      case 5: if constexpr (MR > 5) gemm_tile_any<5, NV>(g, i, pj); break;
      case 6: if constexpr (MR > 6) gemm_tile_any<6, NV>(g, i, pj); break;
      case 7: if constexpr (MR > 7) gemm_tile_any<7, NV>(g, i, pj); break;
      default: break;
    }
  }
}
