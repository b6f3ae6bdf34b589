// Fused multi-head attention with an online softmax (the FlashAttention
// scheme): for a group of R query rows, key blocks of kAttnKB keys are scored
// and weighed into a small buffer, the row sums are updated and P V is
// accumulated into the output rows. No Lq x Lk matrix is ever stored. The
// weights are base-2 exponentials against a fixed reference exponent per row
// (attn_weights_lazy); a block that would overflow or underflow it is redone
// against its own maximum with the sums and outputs rescaled (attn_group).
// K and V are first packed per head (attn_pack_kv): K^T so that keys are the
// vector dimension of the scoring loop, both contiguous per key block.
// Where the raw scores come from is a policy (the QK template argument): fp32
// dot products over packed K^T (AttnF32QK, below), int8 ones (VNNI,
// kernels/attention/qs8_attention_8x2v__avx512vnni.cc) or bf16 ones
// (kernels/attention/bf16_attention_8x2v__avx512bf16.cc); so is P V (the PV
// argument: AttnF32PV below, or the bf16 kernel's). The online softmax is the
// same code for all.
// Included inside an ISA namespace (after vmath.inl).

constexpr int kAttnKB = kAttentionKeyBlock;  // f32_attention_blocking.h

// Packs head h of K and V for attn_block: K^T in blocks of kAttnKB keys
// (kt_h[block][p][j], so a block's scoring reads 16 KB of contiguous memory at
// d = 32), and V as a dense [lk_pad][d] (one head's rows back to back).
// lk_pad is a multiple of kAttnKB; padded keys are zero.
// V of head h as a dense [lk_pad][d]: one head's rows back to back, whole
// vectors where they fit, padded keys zero.
static inline void attn_pack_v(int kv_len, int lk_pad, int d, const float* v, size_t ldv, int h,
                               float* vp) {
  float* vdst = vp + size_t(h) * d * lk_pad;
  for (int j = 0; j < kv_len; ++j) {
    const float* vs = v + size_t(j) * ldv + size_t(h) * d;
    float* vr = vdst + size_t(j) * d;
    int p = 0;
    for (; p + kLanes <= d; p += kLanes) vstore(vr + p, vload(vs + p));
    if (p < d) vstore_n(vr + p, vload_n(vs + p, d - p), d - p);
  }
  for (size_t i = size_t(kv_len) * d; i < size_t(lk_pad) * d; ++i) vdst[i] = 0.0f;
}

static inline void attn_pack_kv(int kv_len, int lk_pad, int d, const float* k, size_t ldk,
                                const float* v, size_t ldv, int h, float* kt, float* vp) {
  float* kdst = kt + size_t(h) * d * lk_pad;
  attn_pack_v(kv_len, lk_pad, d, v, ldv, h, vp);
  // K^T in blocks of kAttnKB keys: a key's row is read once and scattered
  // down its block column (reading columns instead, 1 KB apart, thrashes L1).
  // An ISA with a register transpose does whole 16 x 16 tiles first and
  // leaves the rest here (attn_pack_kt_tiles, AVX-512).
  int j = 0;
#ifdef APRT_ATTN_PACK_KT_TILES
  j = attn_pack_kt_tiles(kv_len, d, k, ldk, h, kdst);
#endif
  for (; j < lk_pad; ++j) {
    float* kb = kdst + size_t(j / kAttnKB) * d * kAttnKB + j % kAttnKB;
    if (j < kv_len) {
      const float* kr = k + size_t(j) * ldk + size_t(h) * d;
      for (int p = 0; p < d; ++p) kb[size_t(p) * kAttnKB] = kr[p];
    } else {
      for (int p = 0; p < d; ++p) kb[size_t(p) * kAttnKB] = 0.0f;
    }
  }
}

// Query rows per task chunk: a key block's K^T and V (32 KB at d = 32) stay in
// L1 while every row group of the chunk uses them.
constexpr int kAttnChunk = kAttentionMaxRows;  // f32_attention_blocking.h

// Floats of per-thread scratch attn_block needs for head width dv vectors.
static inline size_t attn_thread_scratch(int rows, int dv) {
  return size_t(rows) * kAttnKB + size_t(kAttnChunk) * (size_t(dv) * kLanes + 1 + kLanes);
}

// acc[r][t] = q_r . k_j for the S vectors of keys starting at kp (a column
// of a packed K^T block): K^T rows loaded as vectors, q broadcast.
template <int R, int S>
static inline void attn_dots(int d, const float* qh, size_t ldq, const float* kp, V (*acc)[S]) {
#pragma GCC unroll 8
  for (int r = 0; r < R; ++r) {
#pragma GCC unroll 4
    for (int t = 0; t < S; ++t) acc[r][t] = vzero();
  }
  for (int p = 0; p < d; ++p) {
    V kv[S];
#pragma GCC unroll 4
    for (int t = 0; t < S; ++t) kv[t] = vload(kp + size_t(p) * kAttnKB + t * kLanes);
#pragma GCC unroll 8
    for (int r = 0; r < R; ++r) {
      const V qv = vset1(qh[size_t(r) * ldq + p]);
#pragma GCC unroll 4
      for (int t = 0; t < S; ++t) acc[r][t] = vfmadd(qv, kv[t], acc[r][t]);
    }
  }
}

// The fp32 score source: query rows of one head at q (row stride ldq) and a
// head's K^T packed by attn_pack_kv. block(j0) moves to the key block at j0,
// keys(js) to the js-th key of it, rows(g) down g query rows; dots<R, S>
// writes the raw scores q_r . k_j of R rows and S vectors of keys.
struct AttnF32QK {
  const float* q;
  size_t ldq;
  const float* kp;
  int d;
  AttnF32QK rows(int g) const { return {q + size_t(g) * ldq, ldq, kp, d}; }
  AttnF32QK block(int j0) const { return {q, ldq, kp + size_t(j0) * d, d}; }
  AttnF32QK keys(int js) const { return {q, ldq, kp + js, d}; }
  template <int R, int S>
  void dots(V (*acc)[S]) const {
    attn_dots<R, S>(d, q, ldq, kp, acc);
  }
};

// Raw scores of R query rows against S vectors of keys starting at kp (a
// column of a packed K^T block): sbuf[r][j] = q_r . k_j for j < S * kLanes,
// and the rows' running maxima mx. Keys at n and beyond are zero padding:
// their scores become -inf, out of the maximum and weighted 2^-125 (below any
// row sum's rounding) in the exponent pass.
template <int R, int S, class QK>
static inline void attn_score(const QK& qk, int n, float* sbuf, V* mx) {
  V acc[R][S];
  qk.template dots<R, S>(acc);
#pragma GCC unroll 8
  for (int r = 0; r < R; ++r) {
#pragma GCC unroll 4
    for (int t = 0; t < S; ++t) vstore(sbuf + r * kAttnKB + t * kLanes, acc[r][t]);
  }
  if (n >= S * kLanes) {
#pragma GCC unroll 8
    for (int r = 0; r < R; ++r) {
#pragma GCC unroll 4
      for (int t = 0; t < S; ++t) mx[r] = vmax(mx[r], acc[r][t]);
    }
  } else {
    for (int r = 0; r < R; ++r) {
      for (int j = n; j < S * kLanes; ++j) sbuf[r * kAttnKB + j] = -__builtin_inff();
    }
#pragma GCC unroll 8
    for (int r = 0; r < R; ++r) {
#pragma GCC unroll 4
      for (int t = 0; t < S; ++t) mx[r] = vmax(mx[r], vload(sbuf + r * kAttnKB + t * kLanes));
    }
  }
}

// The weights of R query rows against S vectors of keys at kp, against the
// rows' current reference exponents m (mrow) instead of the block's maximum:
// sbuf[r][j] = 2^(vc q_r . k_j - m_r), at least 2^-125 (and at most 2^126
// where the exponential does not saturate to +inf), straight from the score
// registers, and added into the rows' lane sums bsum. Padded
// keys (n and beyond; only where !kFull) get weight 0.
template <int R, int S, bool kFull, class QK>
static inline void attn_score_exp(const QK& qk, int n, V vc, const float* mrow, float* sbuf,
                                  V* bsum) {
  V acc[R][S];
  qk.template dots<R, S>(acc);
#pragma GCC unroll 8
  for (int r = 0; r < R; ++r) {
    const V neg_m = vset1(-mrow[r]);
#pragma GCC unroll 4
    for (int t = 0; t < S; ++t) {
      // Clamped below even where vscale2 would give 0 by itself (AVX-512):
      // unclamped, far-off keys give denormal weights, and the full 224 model
      // measured ~25 % slower per frame that way. Above, 2^126 or +inf fails
      // the sum check. The score is the second operand: x86's max and min
      // return it when it is NaN, so a NaN score stays a NaN weight (its
      // row's output NaN, as the reference's) instead of becoming 2^-125.
      V x = vmax(vset1(-125.0f), vfmadd(acc[r][t], vc, neg_m));
      if constexpr (!kExp2SaturatesHigh) x = vmin(vset1(126.0f), x);
      const V e = vexp2_bounded(x);
      vstore(sbuf + r * kAttnKB + t * kLanes, e);
      if constexpr (kFull) bsum[r] = vadd(bsum[r], e);
    }
  }
  if constexpr (!kFull) {
    for (int r = 0; r < R; ++r) {
      for (int j = n; j < S * kLanes; ++j) sbuf[r * kAttnKB + j] = 0.0f;
#pragma GCC unroll 4
      for (int t = 0; t < S; ++t) bsum[r] = vadd(bsum[r], vload(sbuf + r * kAttnKB + t * kLanes));
    }
  }
}

// One sub-block of SV vectors of keys at kp with `left` keys of the block
// left: the padded variant only where the sub-block runs past them.
template <int R, int SV, class QK>
static inline void attn_score_exp_any(const QK& qk, int left, V vc, const float* ref, float* sbuf,
                                      V* bsum) {
  if (left >= SV * kLanes) {
    attn_score_exp<R, SV, true>(qk, left, vc, ref, sbuf, bsum);
  } else {
    attn_score_exp<R, SV, false>(qk, left, vc, ref, sbuf, bsum);
  }
}

// Weights of a key block against a fixed reference exponent instead of the
// block's maximum (the lazy rescaling of FlashAttention-2): the rows' first
// block against 0 (scaled scores of a trained network are within a few tens
// of log2 units of it), later blocks against the reference the earlier ones
// set. No maximum, no rescaling of sums and outputs, the exponentials taken
// while the scores are still in registers. Exact up to rounding while no
// weight overflows and the row's mass is not lost below the clamp: a row
// one of whose lane sums exceeds 2^60 (a score ~40 nats above the
// reference), or whose first block has no lane sum of 2^-60 (all scores ~40
// nats below 0), returns false with mrow and lrow untouched, and the caller
// redoes the block with its maximum. The row sums stay lane sums (lrow is
// [R][kLanes]) until the chunk's end: no horizontal sum per block.
template <int R, int SV, class QK>
static inline bool attn_weights_lazy(bool first, int kb, const QK& qk, V vc, float* sbuf,
                                     float* mrow, float* lrow) {
  float ref[R];
  for (int r = 0; r < R; ++r) ref[r] = first ? 0.0f : mrow[r];
  V bsum[R];
#pragma GCC unroll 8
  for (int r = 0; r < R; ++r) bsum[r] = vzero();
  for (int js = 0; js < kb;) {
    if (SV > 1 && kb - js <= kLanes) {
      attn_score_exp_any<R, 1>(qk.keys(js), kb - js, vc, ref, sbuf + js, bsum);
      js += kLanes;
    } else {
      attn_score_exp_any<R, SV>(qk.keys(js), kb - js, vc, ref, sbuf + js, bsum);
      js += SV * kLanes;
    }
  }
  // The checks on the lane sums, no horizontal sum: every lane <= 2^60 keeps
  // the block's sum <= 2^64, one lane >= 2^-60 keeps it >= 2^-60 (NaN fails).
  static_assert(kLanes <= 16, "kLanes lanes of at most 2^60 must sum to at most 2^64");
  for (int r = 0; r < R; ++r) {
    if (!vall_le(bsum[r], 0x1p60f) || (first && !vany_ge(bsum[r], 0x1p-60f))) return false;
  }
  for (int r = 0; r < R; ++r) {
    mrow[r] = ref[r];
    vstore(lrow + r * kLanes, vadd(vload(lrow + r * kLanes), bsum[r]));
  }
  return true;
}

// obuf rows (R x DV vectors) = alpha_r * obuf + P V over the block's kb
// keys, P the weights in sbuf; alpha null: no rescaling. V rows of width d
// (DV vectors, the last dcnt[DV - 1] lanes wide) at stride ldv.
template <int R, int DV>
static inline void attn_pv(int kb, const float* vh, size_t ldv, int d, const float* sbuf,
                           const float* alpha, float* obuf) {
  int dcnt[DV];
#pragma GCC unroll 4
  for (int t = 0; t < DV; ++t) {
    const int left = d - t * kLanes;
    dcnt[t] = left < 0 ? 0 : (left > kLanes ? kLanes : left);
  }
  V oacc[R][DV];
#pragma GCC unroll 8
  for (int r = 0; r < R; ++r) {
#pragma GCC unroll 4
    for (int t = 0; t < DV; ++t) {
      oacc[r][t] = vload(obuf + (r * DV + t) * kLanes);
      if (alpha) oacc[r][t] = vmul(oacc[r][t], vset1(alpha[r]));
    }
  }
  // P V: a head width of whole vectors (d = 32 here) loads V unmasked.
  if (dcnt[DV - 1] == kLanes) {
    for (int jj = 0; jj < kb; ++jj) {
      V vv[DV];
#pragma GCC unroll 4
      for (int t = 0; t < DV; ++t) vv[t] = vload(vh + size_t(jj) * ldv + t * kLanes);
#pragma GCC unroll 8
      for (int r = 0; r < R; ++r) {
        const V pv = vset1(sbuf[r * kAttnKB + jj]);
#pragma GCC unroll 4
        for (int t = 0; t < DV; ++t) oacc[r][t] = vfmadd(pv, vv[t], oacc[r][t]);
      }
    }
  } else {
    for (int jj = 0; jj < kb; ++jj) {
      V vv[DV];
#pragma GCC unroll 4
      for (int t = 0; t < DV; ++t) vv[t] = vload_n(vh + size_t(jj) * ldv + t * kLanes, dcnt[t]);
#pragma GCC unroll 8
      for (int r = 0; r < R; ++r) {
        const V pv = vset1(sbuf[r * kAttnKB + jj]);
#pragma GCC unroll 4
        for (int t = 0; t < DV; ++t) oacc[r][t] = vfmadd(pv, vv[t], oacc[r][t]);
      }
    }
  }
#pragma GCC unroll 8
  for (int r = 0; r < R; ++r) {
#pragma GCC unroll 4
    for (int t = 0; t < DV; ++t) vstore(obuf + (r * DV + t) * kLanes, oacc[r][t]);
  }
}

// The fp32 P V: one head's V packed by attn_pack_v ([lk_pad][d]). block(j0)
// moves to the key block at j0; pv<R, DV> accumulates a block's weights
// (attn_pv). The bf16 kernel has its own (x86/bf16_attention_8x2v__avx512bf16.cc).
struct AttnF32PV {
  const float* v;
  int d;
  AttnF32PV block(int j0) const { return {v + size_t(j0) * d, d}; }
  template <int R, int DV>
  void pv(int kb, const float* sbuf, const float* alpha, float* obuf) const {
    attn_pv<R, DV>(kb, v, size_t(d), d, sbuf, alpha, obuf);
  }
};

// One group of R query rows against one key block [j0, j0 + kb): scores,
// online-softmax update, and P V accumulated into obuf (rows of DV vectors);
// lrow holds each row's lane sums.
// The softmax runs in base 2: vc = scale * log2(e), so each weight is
// 2^(vc s - m) with m the running maximum of vc s (kept in mrow); the raw
// scores' maximum is taken in registers while they are stored, and scaling
// and subtracting are one FMA in the exponent pass.
template <int R, int SV, int DV, class QK, class PV>
static inline void attn_group(bool first, int kb, const QK& qk, const PV& pv, V vc, float c,
                              float* sbuf, float* obuf, float* mrow, float* lrow) {
  static_assert(kAttnKB % (SV * kLanes) == 0, "key block must hold whole scoring sub-blocks");
  if (attn_weights_lazy<R, SV>(first, kb, qk, vc, sbuf, mrow, lrow)) {
    pv.template pv<R, DV>(kb, sbuf, nullptr, obuf);
    return;
  }
  V mx[R];
#pragma GCC unroll 8
  for (int r = 0; r < R; ++r) mx[r] = vset1(-__builtin_inff());
  // Sub-blocks of SV vectors of keys; a block's last keys, if they fit one
  // vector, are scored one vector wide (784 = 6 x 128 + 16 keys).
  for (int js = 0; js < kb;) {
    if (SV > 1 && kb - js <= kLanes) {
      attn_score<R, 1>(qk.keys(js), kb - js, sbuf + js, mx);
      js += kLanes;
    } else {
      attn_score<R, SV>(qk.keys(js), kb - js, sbuf + js, mx);
      js += SV * kLanes;
    }
  }
  // New row maxima; the rescale factors of all R rows in one vector exp.
  const int kb_vec = (kb + kLanes - 1) / kLanes * kLanes;
  float diff[R < kLanes ? kLanes : R];
  for (int r = 0; r < R; ++r) {
    const float m_blk = vreduce_max(mx[r]) * c;
    const float m_new = mrow[r] > m_blk ? mrow[r] : m_blk;
    diff[r] = mrow[r] - m_new;
    mrow[r] = m_new;
  }
  for (int r0 = 0; r0 < R; r0 += kLanes) {
    const int n = R - r0 < kLanes ? R - r0 : kLanes;
    vstore_n(diff + r0, vexp2_nonpos(vload_n(diff + r0, n)), n);  // alpha_r
  }
  // Exponentiate; rescale the lane sums and (in registers, below) the outputs.
  for (int r = 0; r < R; ++r) {
    float* srow = sbuf + r * kAttnKB;
    const V neg_m = vset1(-mrow[r]);
    V sum = vzero();
    for (int j = 0; j < kb_vec; j += kLanes) {
      const V e = vexp2_nonpos(vfmadd(vload(srow + j), vc, neg_m));
      vstore(srow + j, e);
      sum = vadd(sum, e);
    }
    vstore(lrow + r * kLanes, vfmadd(vload(lrow + r * kLanes), vset1(diff[r]), sum));
  }
  pv.template pv<R, DV>(kb, sbuf, diff, obuf);
}

// Query rows [q0, q0 + rows) of head h (rows <= kAttnChunk), their scores
// from qk (positioned at row q0 of head h, key 0): key blocks outer, row
// groups of R inner.
template <int R, int SV, int DV, class QK, class PV>
static void attn_chunk(int rows, int kv_len, int d, const QK& qk, const PV& pv, float scale,
                       float* o, size_t ldo, int h, int q0, float* scratch) {
  float* sbuf = scratch;                          // [R][kAttnKB]
  float* obuf = scratch + R * kAttnKB;            // [rows][DV * kLanes]
  float* mrow = obuf + kAttnChunk * DV * kLanes;  // [rows]
  float* lrow = mrow + kAttnChunk;                // [rows][kLanes]: lane sums
  int dcnt[DV];
#pragma GCC unroll 4
  for (int t = 0; t < DV; ++t) {
    const int left = d - t * kLanes;
    dcnt[t] = left < 0 ? 0 : (left > kLanes ? kLanes : left);
  }
  for (int r = 0; r < rows; ++r) {
    mrow[r] = -__builtin_inff();
    vstore(lrow + r * kLanes, vzero());
    for (int t = 0; t < DV; ++t) vstore(obuf + (r * DV + t) * kLanes, vzero());
  }
  const float c = scale * 1.44269504088896341f;  // base-2 softmax (attn_group)
  const V vc = vset1(c);
  for (int j0 = 0; j0 < kv_len; j0 += kAttnKB) {
    const int kb = kv_len - j0 < kAttnKB ? kv_len - j0 : kAttnKB;
    const QK qb = qk.block(j0);  // block j0 / kAttnKB
    const PV pb = pv.block(j0);
    int g = 0;
    for (; g + R <= rows; g += R) {
      attn_group<R, SV, DV>(j0 == 0, kb, qb.rows(g), pb, vc, c, sbuf, obuf + g * DV * kLanes,
                            mrow + g, lrow + g * kLanes);
    }
    const int left = rows - g;
#define APRT_ATTN_TAIL(RR)                                                                     \
  case RR:                                                                                     \
    if constexpr (R > RR) {                                                                    \
      attn_group<RR, SV, DV>(j0 == 0, kb, qb.rows(g), pb, vc, c, sbuf, obuf + g * DV * kLanes, \
                             mrow + g, lrow + g * kLanes);                                     \
    }                                                                                          \
    break;
    switch (left) {
      APRT_ATTN_TAIL(1)
      APRT_ATTN_TAIL(2)
      APRT_ATTN_TAIL(3)
      APRT_ATTN_TAIL(4)
      APRT_ATTN_TAIL(5)
      APRT_ATTN_TAIL(6)
      APRT_ATTN_TAIL(7)
      default: break;
    }
#undef APRT_ATTN_TAIL
  }
  for (int r = 0; r < rows; ++r) {
    const V inv = vset1(1.0f / vreduce_add(vload(lrow + r * kLanes)));
    float* orow = o + size_t(q0 + r) * ldo + size_t(h) * d;
    for (int t = 0; t < DV; ++t) {
      if (dcnt[t] == 0) continue;
      vstore_n(orow + t * kLanes, vmul(vload(obuf + (r * DV + t) * kLanes), inv), dcnt[t]);
    }
  }
}

// Query rows [q0, q0 + rows) of head h, rows <= kAttnChunk, their scores
// from qk (positioned as attn_chunk says), P V by pv (at head h, key 0). Returns
// false if the head width needs more than 8 vectors (the caller then uses the
// reference kernel).
template <int R, int SV, class QK, class PV>
static bool attn_block_qk(int rows, int kv_len, int d, const QK& qk, const PV& pv, float scale,
                          float* o, size_t ldo, int h, int q0, float* scratch) {
  static_assert(R <= 8, "row groups are dispatched up to 8");
#define APRT_ATTN_DV(DVV)                                                         \
  attn_chunk<R, SV, DVV>(rows, kv_len, d, qk, pv, scale, o, ldo, h, q0, scratch); \
  return true;
  switch ((d + kLanes - 1) / kLanes) {
    case 1: APRT_ATTN_DV(1)
    case 2: APRT_ATTN_DV(2)
    case 3: APRT_ATTN_DV(3)
    case 4: APRT_ATTN_DV(4)
    case 5: APRT_ATTN_DV(5)
    case 6: APRT_ATTN_DV(6)
    case 7: APRT_ATTN_DV(7)
    case 8: APRT_ATTN_DV(8)
    default: return false;
  }
#undef APRT_ATTN_DV
}

// The fp32 attention: query rows [q0, q0 + rows) of head h over K and V
// packed by attn_pack_kv.
template <int R, int SV>
static bool attn_block(int rows, int kv_len, int d, const float* q, size_t ldq, const float* kt,
                       const float* vp, int lk_pad, float scale, float* o, size_t ldo, int h,
                       int q0, float* scratch) {
  const AttnF32QK qk{q + size_t(q0) * ldq + size_t(h) * d, ldq, kt + size_t(h) * d * lk_pad, d};
  const AttnF32PV pv{vp + size_t(h) * d * lk_pad, d};
  return attn_block_qk<R, SV>(rows, kv_len, d, qk, pv, scale, o, ldo, h, q0, scratch);
}
