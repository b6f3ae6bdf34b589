// Fused multi-head attention with int8 scores (kernels/attention/qs8_attention.h),
// AVX-512 VNNI: the fp32 kernel of simd/attention_impl.inl with its score
// source replaced. K is quantised per key and head when packed, Q per row and
// head when a chunk starts; vpdpbusd multiplies four u8 x s8 pairs per lane,
// so a score vector at d = 32 is 8 instructions where fp32 takes 32 FMAs.
// The softmax, its lazy rescaling and P V (fp32 V) are unchanged.
#include <immintrin.h>

#include <cstdint>
#include <cstring>

#include "kernels/attention/f32_attention_blocking.h"
#include "kernels/attention/qs8_attention.h"
#include "kernels/common/kernel_types.h"

namespace aprt::kernels {
namespace avx512vnni {
// Order matters: the vector header, then vmath, then the kernels.
// clang-format off
#include "kernels/simd/vec_avx512.h"
#include "kernels/simd/vmath.inl"
#include "kernels/attention/f32_attention_impl.inl"
// clang-format on

// One head's packed K, in the op's scratch at head * attn_q8_head_bytes():
//   k8   [lk_pad / kAttnKB][d / 4][kAttnKB][4] int8 (4 consecutive p of a key
//        together: one vpdpbusd operand is 16 keys x 4 p),
//   sk   [lk_pad] float, the keys' scales,
//   corr [lk_pad] int32, -128 * sum_p k8: Q enters vpdpbusd as u8 = q8 + 128,
//        and the accumulator starts at corr to take the 128s back out.
// Padded keys are zero in all three (score 0; attn_score_exp masks them).
static size_t attn_q8_head_bytes(int lk_pad, int d) {
  return size_t(lk_pad) * d + 2 * sizeof(float) * size_t(lk_pad);
}

// One row of d values (d % 4 == 0, d <= 128) quantised as qs8_attention.h
// says, 16 at a time: max |x| exact, then x * inv rounded half to even by
// vcvtps2dq (MXCSR's default mode) -- the same bits as qs8_round. A lane
// whose x * inv is not finite (a NaN or infinite row: inv is 0 then) is 0,
// as qs8_round makes it, not vcvtps2dq's 0x80000000: d of those summed
// would overflow the key's correction term. The row's NaN scale carries
// the garbage to the scores. Writes d bytes of q8 + bias (0 or 128) to out
// and returns the scale; *sum gets sum_p q8, in [-127 d, 127 d].
static float attn_q8_row(const float* x, int d, int bias, uint8_t* out, int32_t* sum) {
  V amax = vzero();
  __mmask16 nan = 0;
  for (int p = 0; p < d; p += kLanes) {
    const V a = vabs(vload_n(x + p, d - p < kLanes ? d - p : kLanes));
    nan |= _mm512_cmp_ps_mask(a, a, _CMP_UNORD_Q);
    amax = vmax(amax, a);
  }
  // max_ps drops NaNs; the scale must carry one, as qs8_row_scale's does.
  const float m = nan ? __builtin_nanf("") : vreduce_max(amax);
  const float inv = m > 0.0f ? 127.0f / m : 0.0f;
  const V vi = vset1(inv);
  __m512i acc = _mm512_setzero_si512();
  for (int p = 0; p < d; p += kLanes) {
    const int n = d - p < kLanes ? d - p : kLanes;
    const V y = vmul(vload_n(x + p, n), vi);
    // |y| <= 127 wherever it is finite; NaN compares false.
    const __mmask16 finite = _mm512_cmp_ps_mask(vabs(y), vset1(128.0f), _CMP_LT_OQ);
    const __m512i q = _mm512_maskz_cvtps_epi32(finite, y);
    const __mmask16 mk = __mmask16((1u << n) - 1);
    acc = _mm512_mask_add_epi32(acc, mk, acc, q);
    _mm_mask_storeu_epi8(out + p, mk,
                         _mm512_cvtepi32_epi8(_mm512_add_epi32(q, _mm512_set1_epi32(bias))));
  }
  *sum = _mm512_reduce_add_epi32(acc);
  return m / 127.0f;
}

static void attn_q8_pack_k(int kv_len, int lk_pad, int d, const float* k, size_t ldk, int h,
                           uint8_t* base) {
  int8_t* k8 = reinterpret_cast<int8_t*>(base);
  float* sk = reinterpret_cast<float*>(base + size_t(lk_pad) * d);
  int32_t* corr = reinterpret_cast<int32_t*>(sk + lk_pad);
  alignas(64) uint8_t row[128];
  for (int j = 0; j < lk_pad; ++j) {
    int8_t* kb = k8 + size_t(j / kAttnKB) * kAttnKB * d + size_t(j % kAttnKB) * 4;
    int32_t sum = 0;
    if (j < kv_len) {
      sk[j] = attn_q8_row(k + size_t(j) * ldk + size_t(h) * d, d, 0, row, &sum);
    } else {
      std::memset(row, 0, size_t(d));
      sk[j] = 0.0f;
    }
    corr[j] = -128 * sum;
    for (int g = 0; g < d / 4; ++g) std::memcpy(kb + size_t(g) * kAttnKB * 4, row + 4 * g, 4);
  }
}

// The int8 score source (attn_chunk's QK policy): the chunk's query rows
// quantised as u8 = q8 + 128 ([rows][d]) with their scales, and one head's
// packed K.
struct AttnQ8QK {
  const uint8_t* q;
  const float* sq;
  const int8_t* kp;
  const float* sk;
  const int32_t* corr;
  int d;
  AttnQ8QK rows(int g) const { return {q + size_t(g) * d, sq + g, kp, sk, corr, d}; }
  AttnQ8QK block(int j0) const {
    return {q, sq, kp + size_t(j0) * d, sk + j0, corr + j0, d};  // block j0 / kAttnKB
  }
  AttnQ8QK keys(int js) const { return {q, sq, kp + size_t(js) * 4, sk + js, corr + js, d}; }
  template <int R, int S>
  void dots(V (*acc)[S]) const {
    __m512i ia[R][S];
#pragma GCC unroll 8
    for (int r = 0; r < R; ++r) {
#pragma GCC unroll 4
      for (int t = 0; t < S; ++t) ia[r][t] = _mm512_loadu_si512(corr + t * kLanes);
    }
    for (int g = 0; g < d / 4; ++g) {
      __m512i kv[S];
#pragma GCC unroll 4
      for (int t = 0; t < S; ++t) kv[t] = _mm512_loadu_si512(kp + size_t(g) * kAttnKB * 4 + t * 64);
#pragma GCC unroll 8
      for (int r = 0; r < R; ++r) {
        int32_t q4;
        std::memcpy(&q4, q + size_t(r) * d + 4 * g, 4);
        const __m512i qv = _mm512_set1_epi32(q4);
#pragma GCC unroll 4
        for (int t = 0; t < S; ++t) ia[r][t] = _mm512_dpbusd_epi32(ia[r][t], qv, kv[t]);
      }
    }
#pragma GCC unroll 8
    for (int r = 0; r < R; ++r) {
      const V s = vset1(sq[r]);
#pragma GCC unroll 4
      for (int t = 0; t < S; ++t) {
        acc[r][t] = vmul(vmul(_mm512_cvtepi32_ps(ia[r][t]), vload(sk + t * kLanes)), s);
      }
    }
  }
};

// Per-thread floats: the fp32 kernel's, then the chunk's quantised rows and
// their scales.
static size_t attn_q8_thread_scratch(int d) {
  const int dv = (d + kLanes - 1) / kLanes;
  return attn_thread_scratch(8, dv) + size_t(kAttnChunk) * (size_t(d) / 4 + 1);
}

static bool attn_q8_block(int rows, int kv_len, int d, const float* q, size_t ldq,
                          const uint8_t* kq, const float* vp, int lk_pad, float scale, float* o,
                          size_t ldo, int h, int q0, float* scratch) {
  if (d % 4 != 0 || d > 128 || rows > kAttnChunk) return false;
  const int dv = (d + kLanes - 1) / kLanes;
  float* sq = scratch + attn_thread_scratch(8, dv);
  auto* q8 = reinterpret_cast<uint8_t*>(sq + kAttnChunk);
  for (int r = 0; r < rows; ++r) {
    int32_t unused;
    sq[r] =
        attn_q8_row(q + size_t(q0 + r) * ldq + size_t(h) * d, d, 128, q8 + size_t(r) * d, &unused);
  }
  const uint8_t* base = kq + size_t(h) * attn_q8_head_bytes(lk_pad, d);
  const auto* sk = reinterpret_cast<const float*>(base + size_t(lk_pad) * d);
  const AttnQ8QK qk{q8,
                    sq,
                    reinterpret_cast<const int8_t*>(base),
                    sk,
                    reinterpret_cast<const int32_t*>(sk + lk_pad),
                    d};
  const AttnF32PV pv{vp + size_t(h) * d * lk_pad, d};
  return attn_block_qk<8, 2>(rows, kv_len, d, qk, pv, scale, o, ldo, h, q0, scratch);
}
}  // namespace avx512vnni

size_t qs8_attention_kq_bytes__avx512vnni(int heads, int lk_pad, int d) {
  return size_t(heads) * avx512vnni::attn_q8_head_bytes(lk_pad, d);
}
void qs8_attention_pack_kv__avx512vnni(int kv_len, int lk_pad, int d, const float* k, size_t ldk,
                                       const float* v, size_t ldv, int h, uint8_t* kq, float* vp) {
  avx512vnni::attn_q8_pack_k(kv_len, lk_pad, d, k, ldk, h,
                             kq + size_t(h) * avx512vnni::attn_q8_head_bytes(lk_pad, d));
  avx512vnni::attn_pack_v(kv_len, lk_pad, d, v, ldv, h, vp);
}
bool qs8_attention_8x2v__avx512vnni(int rows, int kv_len, int d, const float* q, size_t ldq,
                                    const uint8_t* kq, const float* vp, int lk_pad, float scale,
                                    float* o, size_t ldo, int h, int q0, float* scratch) {
  return avx512vnni::attn_q8_block(rows, kv_len, d, q, ldq, kq, vp, lk_pad, scale, o, ldo, h, q0,
                                   scratch);
}
size_t qs8_attention_scratch__avx512vnni(int d) {
  return avx512vnni::attn_q8_thread_scratch(d);
}

}  // namespace aprt::kernels
