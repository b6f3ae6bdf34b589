// int8 GEMM, 8 rows x 32 columns per tile, AVX-512 VNNI (vpdpbusd: unsigned
// activations x signed weights, four products per 32-bit lane), and the
// activation quantiser. Scheme and epilogue: kernels/gemm/qs8_gemm.h.
#include <immintrin.h>

#include <cstring>

#include "kernels/attention/f32_attention_blocking.h"
#include "kernels/attention/qs8_attention.h"
#include "kernels/common/row_tiles.h"
#include "kernels/gemm/qs8_gemm.h"
#include "kernels/table/kernel_table.h"

namespace aprt::kernels {
namespace {

constexpr int kMr = 8, kNr = 32, kG = 4;

inline int32_t load_a4(const uint8_t* p) {
  int32_t v;
  std::memcpy(&v, p, 4);  // fixed size: one load
  return v;
}
inline int32_t load_a_tail(const uint8_t* p, int n) {  // n (1..3) valid bytes, zero-padded
  uint32_t v = 0;
  for (int i = 0; i < n; ++i) v |= uint32_t(p[i]) << (8 * i);
  return int32_t(v);
}

// acc + the four u8 x s8 products of each 32-bit lane of a and b, in place.
// With the intrinsic, GCC 12 gave the result a register apart from the
// accumulator and copied every accumulator back after every vpdpbusd (two
// register moves per instruction, 64 instructions per 16 products, and
// spills): the tile ran at two thirds of VNNI's rate. The asm ties the
// accumulator to the result, as vfmadd231ps's is.
inline __m512i dpbusd(__m512i acc, __m512i a_u8, __m512i b_s8) {
  __asm__("vpdpbusd %2, %1, %0" : "+v"(acc) : "v"(a_u8), "vm"(b_s8));
  return acc;
}

template <int R>
void tile(const QGemmArgs& g, int r0, int j0, int ncols, const int8_t* wp) {
  __m512i acc[R][2];
  for (int r = 0; r < R; ++r) acc[r][0] = acc[r][1] = _mm512_setzero_si512();
  const uint8_t* a[R];
  for (int r = 0; r < R; ++r) a[r] = g.a + size_t(r0 + r) * g.lda;
  const int full = g.k / kG;
  for (int gi = 0; gi < full; ++gi) {
    const __m512i b0 = _mm512_loadu_si512(wp + size_t(gi) * kNr * kG);
    const __m512i b1 = _mm512_loadu_si512(wp + size_t(gi) * kNr * kG + 64);
#pragma GCC unroll 8
    for (int r = 0; r < R; ++r) {
      const __m512i av = _mm512_set1_epi32(load_a4(a[r] + gi * kG));
      acc[r][0] = dpbusd(acc[r][0], av, b0);
      acc[r][1] = dpbusd(acc[r][1], av, b1);
    }
  }
  if (const int left = g.k - full * kG) {  // a partial last group: never read past a row
    const __m512i b0 = _mm512_loadu_si512(wp + size_t(full) * kNr * kG);
    const __m512i b1 = _mm512_loadu_si512(wp + size_t(full) * kNr * kG + 64);
    for (int r = 0; r < R; ++r) {
      const __m512i av = _mm512_set1_epi32(load_a_tail(a[r] + full * kG, left));
      acc[r][0] = dpbusd(acc[r][0], av, b0);
      acc[r][1] = dpbusd(acc[r][1], av, b1);
    }
  }
  const __m512i za = _mm512_set1_epi32(g.a_zero);
  for (int h = 0; h < 2; ++h) {
    const int cols = ncols - 16 * h;
    if (cols <= 0) break;
    const __mmask16 m = cols >= 16 ? __mmask16(0xFFFF) : __mmask16((1u << cols) - 1);
    const int j = j0 + 16 * h;
    const __m512i cs = _mm512_maskz_loadu_epi32(m, g.w_colsum + j);
    const __m512 mult = _mm512_maskz_loadu_ps(m, g.mult + j);
    const __m512 bias = g.bias ? _mm512_maskz_loadu_ps(m, g.bias + j) : _mm512_setzero_ps();
    const __m512i corr = _mm512_mullo_epi32(za, cs);
    for (int r = 0; r < R; ++r) {
      const __m512i exact = _mm512_sub_epi32(acc[r][h], corr);
      __m512 y = _mm512_fmadd_ps(_mm512_cvtepi32_ps(exact), mult, bias);
      if (g.residual) {
        y = _mm512_add_ps(y, _mm512_maskz_loadu_ps(m, g.residual + size_t(r0 + r) * g.ldr + j));
      }
      if (g.act == Act::kRelu) y = _mm512_max_ps(y, _mm512_setzero_ps());
      _mm512_mask_storeu_ps(g.c + size_t(r0 + r) * g.ldc + j, m, y);
    }
  }
}

void gemm(const QGemmArgs& g, int r0, int r1, int p0, int p1) {
  const size_t panel = size_t((g.k + kG - 1) / kG) * kNr * kG;  // bytes per packed panel
  for_panel_tiles<kMr, kNr>(g.n, r0, r1, p0, p1, [&](auto rows, int r, int j0, int ncols, int p) {
    tile<rows()>(g, r, j0, ncols, g.w_packed + size_t(p) * panel);
  });
}

void quantize(size_t n, const float* x, float inv_scale, int32_t zero, uint8_t* q) {
  const __m512 s = _mm512_set1_ps(inv_scale), lo = _mm512_set1_ps(-512.0f),
               hi = _mm512_set1_ps(512.0f);
  const __m512i z = _mm512_set1_epi32(zero), qmax = _mm512_set1_epi32(255);
  for (size_t i = 0; i < n; i += 16) {
    const size_t left = n - i;
    const __mmask16 m = left >= 16 ? __mmask16(0xFFFF) : __mmask16((1u << left) - 1);
    // max(t, lo) first: a NaN becomes lo, then 0 after the clamp, as in the reference.
    __m512 t =
        _mm512_min_ps(_mm512_max_ps(_mm512_mul_ps(_mm512_maskz_loadu_ps(m, x + i), s), lo), hi);
    __m512i v = _mm512_add_epi32(_mm512_cvtps_epi32(t), z);  // round half to even
    v = _mm512_min_epi32(_mm512_max_epi32(v, _mm512_setzero_si512()), qmax);
    _mm_mask_storeu_epi8(q + i, m, _mm512_cvtepi32_epi8(v));
  }
}

}  // namespace

extern const QKernelSet qs8_kernels__avx512vnni;
const QKernelSet qs8_kernels__avx512vnni = {
    .isa = "avx512vnni",
    .mr = kMr,
    .nr = kNr,
    .kgroup = kG,
    .gemm = gemm,
    .quantize = quantize,
    .dwconv_rows = qu8s8_dwconv2d__avx512,
    .attn_max_rows = kAttentionMaxRows,
    .attn_group_rows = 8,
    .attn_key_block = kAttentionKeyBlock,
    .attn_kq_bytes = qs8_attention_kq_bytes__avx512vnni,
    .attn_pack_kv = qs8_attention_pack_kv__avx512vnni,
    .attn_block = qs8_attention_8x2v__avx512vnni,
    .attn_scratch = qs8_attention_scratch__avx512vnni,
};

}  // namespace aprt::kernels
