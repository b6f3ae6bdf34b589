// f32 fused multi-head attention (online softmax; f32_attention_impl.inl), query
// chunks of kAttnChunk rows in groups of APRT_ATTN_ROWS query rows per block,
// one translation unit per ISA (kernels/simd/isa.h): 8x2v on AVX-512, 4x2v on
// AVX2, 3x4v on NEON.
#include "kernels/table/simd_kernels.h"

namespace aprt::kernels {
namespace APRT_SIMD {
// Order matters: the vector header, then vmath, then the kernels.
// clang-format off
#include APRT_SIMD_VEC
#include "kernels/simd/vmath.inl"
// clang-format on

#if defined(APRT_SIMD_AVX512)
// K^T packing of the keys [0, j_end) that fill whole 16 x 16 tiles (d a
// multiple of 16): 16 key rows loaded, transposed in registers (the standard
// unpack / shuffle / lane-shuffle sequence), stored as 16 rows of 16 keys --
// 16 vector stores where the scalar scatter does 256. Returns j_end, the
// first key left to attn_pack_kv's scalar loop.
static int attn_pack_kt_tiles(int kv_len, int d, const float* k, size_t ldk, int h, float* kdst);
#define APRT_ATTN_PACK_KT_TILES 1
#endif
// clang-format off
#include "kernels/attention/f32_attention_impl.inl"
// clang-format on

#if defined(APRT_SIMD_AVX512)
static int attn_pack_kt_tiles(int kv_len, int d, const float* k, size_t ldk, int h, float* kdst) {
  if (d % 16 != 0) return 0;
  const int j_end = kv_len / 16 * 16;
  for (int j0 = 0; j0 < j_end; j0 += 16) {
    float* kb = kdst + size_t(j0 / kAttnKB) * d * kAttnKB + j0 % kAttnKB;
    for (int p0 = 0; p0 < d; p0 += 16) {
      __m512 r[16], t[16], u[16];
      for (int i = 0; i < 16; ++i)
        r[i] = _mm512_loadu_ps(k + size_t(j0 + i) * ldk + size_t(h) * d + p0);
      for (int i = 0; i < 8; ++i) {
        t[2 * i] = _mm512_unpacklo_ps(r[2 * i], r[2 * i + 1]);
        t[2 * i + 1] = _mm512_unpackhi_ps(r[2 * i], r[2 * i + 1]);
      }
      for (int i = 0; i < 4; ++i) {
        u[4 * i] = _mm512_shuffle_ps(t[4 * i], t[4 * i + 2], 0x44);
        u[4 * i + 1] = _mm512_shuffle_ps(t[4 * i], t[4 * i + 2], 0xEE);
        u[4 * i + 2] = _mm512_shuffle_ps(t[4 * i + 1], t[4 * i + 3], 0x44);
        u[4 * i + 3] = _mm512_shuffle_ps(t[4 * i + 1], t[4 * i + 3], 0xEE);
      }
      // u[4i + c], 128-bit lane L: column 4L + c of rows 4i .. 4i + 3.
      for (int c = 0; c < 4; ++c) {
        const __m512 v0 = _mm512_shuffle_f32x4(u[c], u[4 + c], 0x88);
        const __m512 v1 = _mm512_shuffle_f32x4(u[c], u[4 + c], 0xDD);
        const __m512 w0 = _mm512_shuffle_f32x4(u[8 + c], u[12 + c], 0x88);
        const __m512 w1 = _mm512_shuffle_f32x4(u[8 + c], u[12 + c], 0xDD);
        _mm512_storeu_ps(kb + size_t(p0 + c) * kAttnKB, _mm512_shuffle_f32x4(v0, w0, 0x88));
        _mm512_storeu_ps(kb + size_t(p0 + 4 + c) * kAttnKB, _mm512_shuffle_f32x4(v1, w1, 0x88));
        _mm512_storeu_ps(kb + size_t(p0 + 8 + c) * kAttnKB, _mm512_shuffle_f32x4(v0, w0, 0xDD));
        _mm512_storeu_ps(kb + size_t(p0 + 12 + c) * kAttnKB, _mm512_shuffle_f32x4(v1, w1, 0xDD));
      }
    }
  }
  return j_end;
}
#endif
}  // namespace APRT_SIMD

void APRT_SIMD_NAME(f32_attention_pack_kv, )(int kv_len, int lk_pad, int d, const float* k,
                                             size_t ldk, const float* v, size_t ldv, int h,
                                             float* kt, float* vp) {
  APRT_SIMD::attn_pack_kv(kv_len, lk_pad, d, k, ldk, v, ldv, h, kt, vp);
}
bool APRT_SIMD_NAME(f32_attention_, APRT_ATTN_TILE)(int rows, int kv_len, int d, const float* q,
                                                    size_t ldq, const float* kt, const float* vp,
                                                    int lk_pad, float scale, float* o, size_t ldo,
                                                    int h, int q0, float* scratch) {
  return APRT_SIMD::attn_block<APRT_ATTN_ROWS, APRT_ATTN_NV>(rows, kv_len, d, q, ldq, kt, vp,
                                                             lk_pad, scale, o, ldo, h, q0, scratch);
}
size_t APRT_SIMD_NAME(f32_attention_scratch, )(int d) {
  return APRT_SIMD::attn_thread_scratch(APRT_ATTN_ROWS,
                                        (d + APRT_SIMD::kLanes - 1) / APRT_SIMD::kLanes);
}

}  // namespace aprt::kernels
