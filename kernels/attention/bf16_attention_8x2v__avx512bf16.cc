// Fused multi-head attention in bf16 (kernels/attention/bf16_attention.h),
// AVX-512 BF16: the fp32 kernel of simd/attention_impl.inl with both of its
// products replaced. vdpbf16ps adds two bf16 products per fp32 lane, so a
// score vector at d = 32 is 16 instructions where fp32 takes 32 FMAs, and so
// is P V per pair of keys. The products are exact (8-bit mantissas), the
// sums fp32; the online softmax, its lazy rescaling and the row sums are the
// fp32 kernel's, over the unrounded weights.
#include <immintrin.h>

#include <cstdint>
#include <cstring>

#include "kernels/attention/f32_attention_blocking.h"
#include "kernels/common/kernel_types.h"
#include "kernels/table/kernel_table.h"

namespace aprt::kernels {
namespace avx512bf16 {
// Order matters: the vector header, then vmath, then the kernels.
// clang-format off
#include "kernels/simd/vec_avx512.h"
#include "kernels/simd/vmath.inl"
#include "kernels/attention/f32_attention_impl.inl"
// clang-format on

// One head's packed K and V, at head * bf16_head_elems() bf16 values of the
// op's scratch:
//   K  [lk_pad / kAttnKB][d / 2][kAttnKB][2]: two consecutive p of a key
//      together, so one 64-byte load is the operand of 16 keys x 2 p;
//   V  [lk_pad / 2][dp][2]: two consecutive keys of a channel together (one
//      load is 16 channels x 2 keys), dp = d rounded up to 16 (zero lanes).
// Padded keys are zero in both.
static int bf16_dp(int d) {
  return (d + kLanes - 1) / kLanes * kLanes;
}
static size_t bf16_head_elems(int lk_pad, int d) {
  return size_t(lk_pad) * (size_t(d) + size_t(bf16_dp(d)));
}

// n <= 16 floats at x to bf16 (vcvtneps2bf16: round to nearest even, the
// rounding of kernels/common/bf16.h), as 16 bf16 lanes (zero past n).
static inline __m256i bf16_cvt(const float* x, int n) {
  return reinterpret_cast<__m256i>(_mm512_cvtneps_pbh(vload_n(x, n)));
}

static void bf16_pack_kv(int kv_len, int lk_pad, int d, const float* k, size_t ldk, const float* v,
                         size_t ldv, int h, uint16_t* base) {
  if (d % 2 != 0 || d > 128) return;  // widths bf16_block refuses too
  uint16_t* kp = base;
  uint16_t* vp = base + size_t(lk_pad) * d;
  const int dp = bf16_dp(d);
  alignas(64) uint16_t row[128];
  for (int j = 0; j < lk_pad; ++j) {
    if (j < kv_len) {
      const float* kr = k + size_t(j) * ldk + size_t(h) * d;
      for (int p = 0; p < d; p += kLanes) {
        const int n = d - p < kLanes ? d - p : kLanes;
        _mm256_mask_storeu_epi16(row + p, __mmask16((1u << n) - 1), bf16_cvt(kr + p, n));
      }
    } else {
      std::memset(row, 0, sizeof(uint16_t) * size_t(d));
    }
    uint16_t* kb = kp + size_t(j / kAttnKB) * kAttnKB * d + size_t(j % kAttnKB) * 2;
    for (int g = 0; g < d / 2; ++g) std::memcpy(kb + size_t(g) * kAttnKB * 2, row + 2 * g, 4);
  }
  // Lanes 2c and 2c + 1 of the interleave: channel c of the first and of the
  // second key (the two keys' 16 bf16 each in the low and high half).
  alignas(64) static constexpr uint16_t kInterleave[32] = {
      0, 16, 1, 17, 2,  18, 3,  19, 4,  20, 5,  21, 6,  22, 7,  23,
      8, 24, 9, 25, 10, 26, 11, 27, 12, 28, 13, 29, 14, 30, 15, 31};
  const __m512i idx = _mm512_load_si512(kInterleave);
  for (int i = 0; i < lk_pad / 2; ++i) {
    for (int c = 0; c < dp; c += kLanes) {
      const int n = d - c < kLanes ? (d - c > 0 ? d - c : 0) : kLanes;
      __m256i a = _mm256_setzero_si256(), b = _mm256_setzero_si256();
      if (2 * i < kv_len && n > 0) a = bf16_cvt(v + size_t(2 * i) * ldv + size_t(h) * d + c, n);
      if (2 * i + 1 < kv_len && n > 0)
        b = bf16_cvt(v + size_t(2 * i + 1) * ldv + size_t(h) * d + c, n);
      const __m512i ab = _mm512_inserti64x4(_mm512_castsi256_si512(a), b, 1);
      _mm512_storeu_si512(vp + (size_t(i) * dp + c) * 2, _mm512_permutexvar_epi16(idx, ab));
    }
  }
}

static inline __m512bh bf16_pairs(const uint16_t* p) {
  int32_t pair;
  std::memcpy(&pair, p, 4);
  return reinterpret_cast<__m512bh>(_mm512_set1_epi32(pair));
}

// The bf16 score source (attn_chunk's QK policy): the chunk's query rows in
// bf16 ([rows][d]) and one head's packed K.
struct AttnBf16QK {
  const uint16_t* q;
  const uint16_t* kp;
  int d;
  AttnBf16QK rows(int g) const { return {q + size_t(g) * d, kp, d}; }
  AttnBf16QK block(int j0) const { return {q, kp + size_t(j0) * d, d}; }  // block j0 / kAttnKB
  AttnBf16QK keys(int js) const { return {q, kp + size_t(js) * 2, d}; }
  template <int R, int S>
  void dots(V (*acc)[S]) const {
#pragma GCC unroll 8
    for (int r = 0; r < R; ++r) {
#pragma GCC unroll 4
      for (int t = 0; t < S; ++t) acc[r][t] = vzero();
    }
    for (int g = 0; g < d / 2; ++g) {
      __m512bh kv[S];
#pragma GCC unroll 4
      for (int t = 0; t < S; ++t) {
        kv[t] = reinterpret_cast<__m512bh>(
            _mm512_loadu_si512(kp + (size_t(g) * kAttnKB + size_t(t) * kLanes) * 2));
      }
#pragma GCC unroll 8
      for (int r = 0; r < R; ++r) {
        const __m512bh qv = bf16_pairs(q + size_t(r) * d + 2 * g);
#pragma GCC unroll 4
        for (int t = 0; t < S; ++t) acc[r][t] = _mm512_dpbf16_ps(acc[r][t], qv, kv[t]);
      }
    }
  }
};

// The bf16 P V (attn_group's PV policy): a block's weights rounded to bf16
// into pbuf ([8][kAttnKB]), then two keys per vdpbf16ps over the pair-packed
// V of one head (at the block).
struct AttnBf16PV {
  const uint16_t* v;
  int dp;
  uint16_t* pbuf;
  AttnBf16PV block(int j0) const { return {v + size_t(j0) * dp, dp, pbuf}; }
  template <int R, int DV>
  void pv(int kb, const float* sbuf, const float* alpha, float* obuf) const {
    // Weights past kb up to the vector are 0 or 2^-125 (attn_score_exp,
    // attn_group) against zero V: a pair may straddle kb.
    const int kb_vec = (kb + kLanes - 1) / kLanes * kLanes;
    for (int r = 0; r < R; ++r) {
      for (int j = 0; j < kb_vec; j += kLanes) {
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(pbuf + r * kAttnKB + j),
                            bf16_cvt(sbuf + r * kAttnKB + j, kLanes));
      }
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
    for (int i = 0; i < (kb + 1) / 2; ++i) {
      __m512bh vv[DV];
#pragma GCC unroll 4
      for (int t = 0; t < DV; ++t) {
        vv[t] = reinterpret_cast<__m512bh>(
            _mm512_loadu_si512(v + (size_t(i) * dp + size_t(t) * kLanes) * 2));
      }
#pragma GCC unroll 8
      for (int r = 0; r < R; ++r) {
        const __m512bh pw = bf16_pairs(pbuf + r * kAttnKB + 2 * i);
#pragma GCC unroll 4
        for (int t = 0; t < DV; ++t) oacc[r][t] = _mm512_dpbf16_ps(oacc[r][t], pw, vv[t]);
      }
    }
#pragma GCC unroll 8
    for (int r = 0; r < R; ++r) {
#pragma GCC unroll 4
      for (int t = 0; t < DV; ++t) vstore(obuf + (r * DV + t) * kLanes, oacc[r][t]);
    }
  }
};

// Per-thread floats: the fp32 kernel's, then the chunk's bf16 query rows and
// the block's bf16 weights.
static size_t bf16_thread_scratch(int d) {
  const int dv = (d + kLanes - 1) / kLanes;
  return attn_thread_scratch(8, dv) + (size_t(kAttnChunk) * d + 8 * kAttnKB) / 2;
}

static bool bf16_block(int rows, int kv_len, int d, const float* q, size_t ldq, const uint16_t* kv,
                       int lk_pad, float scale, float* o, size_t ldo, int h, int q0,
                       float* scratch) {
  if (d % 2 != 0 || d > 128 || rows > kAttnChunk) return false;
  const int dv = (d + kLanes - 1) / kLanes;
  auto* q16 = reinterpret_cast<uint16_t*>(scratch + attn_thread_scratch(8, dv));
  uint16_t* pbuf = q16 + size_t(kAttnChunk) * d;
  for (int r = 0; r < rows; ++r) {
    const float* qr = q + size_t(q0 + r) * ldq + size_t(h) * d;
    for (int p = 0; p < d; p += kLanes) {
      const int n = d - p < kLanes ? d - p : kLanes;
      _mm256_mask_storeu_epi16(q16 + size_t(r) * d + p, __mmask16((1u << n) - 1),
                               bf16_cvt(qr + p, n));
    }
  }
  const uint16_t* base = kv + size_t(h) * bf16_head_elems(lk_pad, d);
  const AttnBf16QK qk{q16, base, d};
  const AttnBf16PV pv{base + size_t(lk_pad) * d, bf16_dp(d), pbuf};
  return attn_block_qk<8, 2>(rows, kv_len, d, qk, pv, scale, o, ldo, h, q0, scratch);
}

size_t kv_bytes(int heads, int lk_pad, int d) {
  return size_t(heads) * bf16_head_elems(lk_pad, d) * sizeof(uint16_t);
}
void pack_kv(int kv_len, int lk_pad, int d, const float* k, size_t ldk, const float* v, size_t ldv,
             int h, uint16_t* kv) {
  bf16_pack_kv(kv_len, lk_pad, d, k, ldk, v, ldv, h, kv + size_t(h) * bf16_head_elems(lk_pad, d));
}

}  // namespace avx512bf16

extern const Bf16AttentionKernels bf16_attention_kernels__avx512bf16;
const Bf16AttentionKernels bf16_attention_kernels__avx512bf16 = {
    .isa = "avx512bf16",
    .max_rows = kAttentionMaxRows,
    .group_rows = 8,
    .key_block = kAttentionKeyBlock,
    .kv_bytes = avx512bf16::kv_bytes,
    .pack_kv = avx512bf16::pack_kv,
    .block = avx512bf16::bf16_block,
    .scratch = avx512bf16::bf16_thread_scratch,
};

}  // namespace aprt::kernels
